// math.normalize.<type>: v / |v|, and 0 for the zero vector.
#include "nodes/node_common.h"

#include <cmath>

namespace specula::nodes {
namespace {
template <int W>
struct Normalize {
    static void run(EvalContext& c, const Instr& i) {
        const float* v = c.r + i.in[0];
        float l2 = v[0] * v[0];
        for (int k = 1; k < W; ++k) l2 += v[k] * v[k];
        float l = std::sqrt(l2);
        for (int k = 0; k < W; ++k) c.r[i.out[0] + k] = l2 > 0.f ? v[k] / l : 0.f;
    }
};
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "normalize", vectorTypes(), "Unit vector v/|v| (0 for v = 0).", [](NodeSpec& s, TypeDesc t) {
        s.inputs = {port("v", t, 0.f, "vector")};
        s.outputs = {PortSpec::out("out", t, "v/|v|")};
        s.cpu = byWidth<Normalize>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
