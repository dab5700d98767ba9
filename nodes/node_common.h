// Shared helpers for node files: the declaration every node starts from (declareNode), typed-variant registration
// (one file registers e.g. math.add.float, math.add.vec2, math.add.color3, math.add.vector3), component-wise CPU
// kernels by width, and the one-statement registration of a node and of a category's notes.
#pragma once

#include "core/graph/node_params.h"
#include "core/graph/node_spec.h"

#include <functional>
#include <string>
#include <type_traits>
#include <utility>
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

// The declaration every node starts from, named by its id "<category>.<name>": the category, the doc, and the GLSL
// function spc_<category>_<name> in nodes/<category>/<name>/<name>.glsl (the folder layout of docs/contributing.md).
inline NodeSpec declareNode(const std::string& id, std::string doc) {
    const size_t dot = id.find('.');
    const std::string category = id.substr(0, dot), name = id.substr(dot + 1);
    NodeSpec s;
    s.id = id;
    s.category = category;
    s.doc = std::move(doc);
    s.glslFunction = "spc_" + category + "_" + name;
    s.glslFile = category + "/" + name + "/" + name + ".glsl";
    return s;
}
// The batch entry of a node's CPU function (NodeSpec::cpuBatch, Program::shadeBatch): F inlined into one loop over the
// batch's points, so the interpreter calls the node once per batch and consecutive points' dependent divisions and
// square roots overlap (issue 37). The same arithmetic per point as F, so images keep their bits. flatten: GCC kept F
// (the GGX node's 256 instructions) a call per point. Its own gain is not measured apart: with the three other graph
// changes of issue 37's third slice, callgrind counts 882 instead of 938 instructions per point of bench_graph's batch
// and interleaved rounds gave graph / direct 1.155 instead of 1.228 (medians); harness times are not quoted, since
// code placement alone moves them by about 10 % (docs/performance.md).
template <CpuFn F>
__attribute__((flatten)) void batchOf(EvalContext* ctx, size_t n, const Instr& ins) {
    for (size_t k = 0; k < n; ++k) F(ctx[k], ins);
}
// ... with the parts most nodes have: the parameter struct (its ports are the inputs), the outputs, the CPU entry.
template <class P>
NodeSpec declareNode(const std::string& id, std::string doc, const NodeParams<P>& params, const OutputList& outputs,
                     CpuFn cpu, uint32_t flags = 0) {
    NodeSpec s = declareNode(id, std::move(doc));
    params.describe(s);
    s.outputs = outputs.ports();
    s.cpu = cpu;
    s.flags = flags;
    return s;
}
// ... for a Fresnel pattern node: pure, and its GLSL function is spc_fresnel_<name>_node, because the prelude's
// spc_fresnel_<name> is the Fresnel term itself, which the node's function calls (and the BSDFs call too).
template <class P>
NodeSpec fresnelNode(const std::string& id, std::string doc, const NodeParams<P>& params, const OutputList& outputs,
                     CpuFn cpu) {
    NodeSpec s = declareNode(id, std::move(doc), params, outputs, cpu, kPure);
    s.glslFunction += "_node";
    return s;
}
// ... for a node without inputs whose outputs are listed in order (e.g. a geometry node: see setOutputs).
inline NodeSpec declareNode(const std::string& id, std::string doc, std::vector<PortSpec> outputs, CpuFn cpu,
                            uint32_t flags = 0) {
    NodeSpec s = declareNode(id, std::move(doc));
    s.outputs = std::move(outputs);
    s.cpu = cpu;
    s.flags = flags;
    return s;
}

// Writes the node's outputs in declaration order, one value each (float, Vec2 or Vec3 of the port's width).
template <class... T>
inline void setOutputs(EvalContext& c, const Instr& i, const T&... values) {
    uint8_t k = 0;
    (set(c, i, OutPort<T>{k++}, values), ...);
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


// The declarations "<family>.<name>.<type>" for every type in 'types'; 'fill' sets ports/cpu per type.
template <class Fill>
std::vector<NodeSpec> typedNodes(const std::string& family, const std::string& name, const std::vector<TypeDesc>& types,
                                 const std::string& doc, Fill fill) {
    std::vector<NodeSpec> specs;
    for (TypeDesc t : types) {
        NodeSpec s;
        s.id = family + "." + name + "." + typeName(t);
        s.category = family;
        s.doc = doc;
        s.flags = kPure;
        s.glslFunction = "spc_" + family + "_" + name;
        s.glslFile = family + "/" + name + "/" + name + ".glsl";
        fill(s, t);
        specs.push_back(std::move(s));
    }
    return specs;
}

// The CPU entries of a width-generic family by register width (1, 2 or 3 floats).
struct WidthKernels {
    CpuFn w1, w2, w3;
    CpuFn of(TypeDesc t) const {
        switch (typeWidth(t)) {
            case 1: return w1;
            case 2: return w2;
            default: return w3;
        }
    }
};

// math.<name>.<type> for every type: inputs ports(type), the output "out" (a float where 'scalarOut', else of the
// variant's type) and the CPU entry of the type's width.
inline std::vector<NodeSpec> widthFamily(const std::string& name, const std::vector<TypeDesc>& types,
                                         const std::string& doc, const std::string& outDoc, bool scalarOut,
                                         const std::function<std::vector<PortSpec>(TypeDesc)>& ports,
                                         const WidthKernels& kernels) {
    return typedNodes("math", name, types, doc, [&](NodeSpec& s, TypeDesc t) {
        s.inputs = ports(t);
        s.outputs = {PortSpec::out("out", scalarOut ? TypeDesc::Float : t, outDoc)};
        s.cpu = kernels.of(t);
    });
}

// A family F (a struct in the node file's unnamed namespace) whose F::Args<W> declares its ports (declare(type)) and
// computes the single output (eval(): a float, or FloatN<W> of the variant's type). F is a type, not a template
// template argument: GCC 12 gives templates instantiated with an unnamed-namespace class template as a template
// template argument vague linkage, so two node files' families with the same name would be merged by the linker.
template <class F>
struct FamilyKernel {
    template <int W>
    static void run(EvalContext& c, const Instr& i) {
        using Args = typename F::template Args<W>;
        static const NodeParams<Args> kIn = Args::declare(widthType<W>());
        setSingleOutput(c, i, kIn.read(c, i).eval());
    }
};
template <class F>
std::vector<NodeSpec> mathNodes(const std::string& name, const std::vector<TypeDesc>& types, const std::string& doc,
                                const std::string& outDoc) {
    constexpr bool scalarOut = std::is_same_v<decltype(std::declval<const typename F::template Args<2>&>().eval()), float>;
    auto ports = [](TypeDesc t) {
        switch (typeWidth(t)) {
            case 1: return F::template Args<1>::declare(t).ports();
            case 2: return F::template Args<2>::declare(t).ports();
            default: return F::template Args<3>::declare(t).ports();
        }
    };
    return widthFamily(name, types, doc, outDoc, scalarOut, ports,
                       {&FamilyKernel<F>::template run<1>, &FamilyKernel<F>::template run<2>,
                        &FamilyKernel<F>::template run<3>});
}
// ... of a binary component-wise operation over every math type (math.add, sub, mul, div, pow).
template <float (*Op)(float, float)>
std::vector<NodeSpec> binaryMath(const std::string& name, const std::string& doc, const std::string& outDoc,
                                 const OperandDoc& a, const OperandDoc& b) {
    auto ports = [&](TypeDesc t) { return portsByWidth<BinaryArgs>(t, a, b); };
    return widthFamily(name, mathTypes(), doc, outDoc, false, ports,
                       {&Binary<Op>::template K<1>::run, &Binary<Op>::template K<2>::run,
                        &Binary<Op>::template K<3>::run});
}

}  // namespace specula::nodes

namespace specula::nodes {
inline void addNodes(NodeRegistry& r, NodeSpec s) { r.add(std::move(s)); }
inline void addNodes(NodeRegistry& r, std::vector<NodeSpec> specs) {
    for (NodeSpec& s : specs) r.add(std::move(s));
}
}  // namespace specula::nodes

// A node file whose declaration is one expression, a NodeSpec or several: SPECULA_REGISTER_NODE(declareNode(...)).
#define SPECULA_REGISTER_NODE(...)                                                                  \
    namespace {                                                                                     \
    void specula_register_node(::specula::graph::NodeRegistry& r) { ::specula::nodes::addNodes(r, __VA_ARGS__); } \
    }                                                                                               \
    SPECULA_REGISTER_NODES(specula_register_node)

// The notes of a category (what its nodes share; docs/nodes.md shows them under the category's heading), declared
// once, in nodes/<category>/category.cpp.
#define SPECULA_DESCRIBE_CATEGORY(category, notes)                                                             \
    namespace {                                                                                               \
    void specula_describe_category(::specula::graph::NodeRegistry& r) { r.describeCategory(category, notes); } \
    }                                                                                                         \
    SPECULA_REGISTER_NODES(specula_describe_category)
