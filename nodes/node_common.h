// Shared helpers for node files: typed-variant registration (one file registers e.g. math.add.float,
// math.add.vec2, math.add.color3, math.add.vector3) and component-wise CPU kernels by width.
#pragma once

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

// A port of type t whose default is d in every component, sampled in [lo, hi] by the parity suite.
inline PortSpec port(std::string name, TypeDesc t, float d, std::string doc, float lo = -2.f, float hi = 2.f) {
    return std::move(PortSpec::make(std::move(name), t, {d, d, d}, std::move(doc))).range(lo, hi);
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

// Component-wise kernels: out[k] = Op(a[k], b[k]) / Op(a[k], b[k], c[k]) over the type's width.
template <float (*Op)(float, float)>
struct Binary {
    template <int W>
    struct K {
        static void run(EvalContext& c, const Instr& i) {
            const float* a = c.r + i.in[0];
            const float* b = c.r + i.in[1];
            float* o = c.r + i.out[0];
            for (int k = 0; k < W; ++k) o[k] = Op(a[k], b[k]);
        }
    };
};
template <float (*Op)(float, float, float)>
struct Ternary {
    template <int W>
    struct K {
        static void run(EvalContext& c, const Instr& i) {
            const float* a = c.r + i.in[0];
            const float* b = c.r + i.in[1];
            const float* d = c.r + i.in[2];
            float* o = c.r + i.out[0];
            for (int k = 0; k < W; ++k) o[k] = Op(a[k], b[k], d[k]);
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
