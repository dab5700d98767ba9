// math.length.<type>: Euclidean length |v|.
#include "nodes/node_common.h"

#include <cmath>

namespace specula::nodes {
namespace {
template <int W>
struct Length {
    static void run(EvalContext& c, const Instr& i) {
        const float* v = c.r + i.in[0];
        float l2 = v[0] * v[0];
        for (int k = 1; k < W; ++k) l2 += v[k] * v[k];
        c.r[i.out[0]] = std::sqrt(l2);
    }
};
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "length", vectorTypes(), "Euclidean length |v|.", [](NodeSpec& s, TypeDesc t) {
        s.inputs = {port("v", t, 0.f, "vector")};
        s.outputs = {PortSpec::out("out", TypeDesc::Float, "|v|")};
        s.cpu = byWidth<Length>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
