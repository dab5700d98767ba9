// closure.mix: a·(1 − t) + b·t (lobe weights and emissions scaled).
#include "nodes/node_common.h"

#include "core/render/bsdf.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) {
    int a = inClosure(c, i, 0), b = inClosure(c, i, 1), o = outClosure(c, i, 0);
    float t = inF(c, i, 2);
    Closure& dst = *c.closures[o];
    dst.clear();
    dst.append(*c.closures[a], Color3(1.f - t));
    dst.append(*c.closures[b], Color3(t));
    c.emission[o] = c.emission[a] * (1.f - t) + c.emission[b] * t;
}
void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "closure.mix";
    s.category = "closure";
    s.doc = "Blend of two closures a·(1 − t) + b·t.";
    s.inputs = {PortSpec::closure("a", "closure at t = 0"), PortSpec::closure("b", "closure at t = 1"),
                std::move(PortSpec::f("t", 0.5f, "blend factor")).range(0.f, 1.f)};
    s.outputs = {PortSpec::out("bsdf", TypeDesc::Closure, "a·(1 − t) + b·t")};
    s.cpu = &cpu;
    s.glslFunction = "spc_closure_mix";
    s.glslFile = "closure/mix/mix.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
