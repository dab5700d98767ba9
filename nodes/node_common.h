// Shared helpers for node files: typed-variant registration (one file registers e.g. math.add.float,
// math.add.vec2, math.add.color3, math.add.vector3) and component-wise CPU kernels by width.
#pragma once

#include "core/graph/node_params.h"
#include "core/graph/node_spec.h"

#include <string>
#include <vector>

namespace specula::nodes {

using namespace specula::graph;

inline const std::vector<TypeDesc>& mathTypes() {
    static const std::vector<TypeDesc> t = {TypeDesc::Float, TypeDesc::Vec2, TypeDesc::Color3, TypeDesc::Vector3};
    return t;
}
inline const std::vector<TypeDesc>& vectorTypes() {
    static const std::vector<TypeDesc> t = {TypeDesc::Vec2, TypeDesc::Vector3};
    return t;
}

// The canonical port type of a register width (reading lists of width-generic families are built with it).
template <int W>
constexpr TypeDesc widthType() {
    return W == 1 ? TypeDesc::Float : W == 2 ? TypeDesc::Vec2 : TypeDesc::Vector3;
}

// Default, documentation and soft range of one operand of a width-generic family.
struct OperandDoc {
    float def = 0.f;
    std::string doc;
    float lo = -2.f, hi = 2.f;
};

// Writes the value of a node's single output (the typed math families have exactly one).
template <class T>
inline void setSingleOutput(EvalContext& c, const Instr& i, const T& v) {
    set(c, i, OutPort<T>{0}, v);
}

// Calls F::template ports<W>(t, args...) for the width of t and returns the PortSpecs.
template <template <int> class Family, class... Args>
std::vector<PortSpec> portsByWidth(TypeDesc t, const Args&... args) {
    switch (typeWidth(t)) {
        case 1: return Family<1>::declare(t, args...).ports();
        case 2: return Family<2>::declare(t, args...).ports();
        default: return Family<3>::declare(t, args...).ports();
    }
}

// Dispatch a kernel template on the register width of t.
template <template <int> class K>
CpuFn byWidth(TypeDesc t) {
    switch (typeWidth(t)) {
        case 1: return &K<1>::run;
        case 2: return &K<2>::run;
        default: return &K<3>::run;
    }
}

}  // namespace specula::nodes

namespace specula::nodes {

// Binary component-wise families (math.add, sub, mul, div, pow): ports a and b of the family type.
template <int W>
struct BinaryArgs {
    FloatN<W> a, b;
    static NodeParams<BinaryArgs> declare(TypeDesc t, const OperandDoc& a = {}, const OperandDoc& b = {}) {
        return NodeParams<BinaryArgs>()
            .typed("a", &BinaryArgs::a, t, a.def, a.doc).range(a.lo, a.hi)
            .typed("b", &BinaryArgs::b, t, b.def, b.doc).range(b.lo, b.hi);
    }
};
template <float (*Op)(float, float)>
struct Binary {
    template <int W>
    struct K {
        static void run(EvalContext& c, const Instr& i) {
            static const NodeParams<BinaryArgs<W>> kIn = BinaryArgs<W>::declare(widthType<W>());
            const BinaryArgs<W> p = kIn.read(c, i);
            FloatN<W> o;
            for (int k = 0; k < W; ++k) o[k] = Op(p.a[k], p.b[k]);
            setSingleOutput(c, i, o);
        }
    };
};


// Registers "<family>.<name>.<type>" for every type in 'types'; 'fill' sets ports/cpu per type.
template <class Fill>
void registerTyped(NodeRegistry& reg, const std::string& family, const std::string& name,
                   const std::vector<TypeDesc>& types, const std::string& doc, Fill fill) {
    for (TypeDesc t : types) {
        NodeSpec s;
        s.id = family + "." + name + "." + typeName(t);
        s.category = family;
        s.doc = doc;
        s.flags = kPure;
        s.glslFunction = "spc_" + family + "_" + name;
        s.glslFile = family + "/" + name + "/" + name + ".glsl";
        fill(s, t);
        reg.add(std::move(s));
    }
}

}  // namespace specula::nodes
