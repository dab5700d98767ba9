// math.remap.<type>: maps x linearly from [in_min, in_max] to [out_min, out_max] (no clamping);
// out_min where in_max == in_min.
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
template <int W>
struct Remap {
    static void run(EvalContext& c, const Instr& i) {
        const float* x = c.r + i.in[0];
        const float* a = c.r + i.in[1];
        const float* b = c.r + i.in[2];
        const float* p = c.r + i.in[3];
        const float* q = c.r + i.in[4];
        float* o = c.r + i.out[0];
        for (int k = 0; k < W; ++k) {
            float d = b[k] - a[k];
            o[k] = d == 0.f ? p[k] : p[k] + (x[k] - a[k]) / d * (q[k] - p[k]);
        }
    }
};
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "remap", mathTypes(), "Linear remap of x from [in_min, in_max] to [out_min, out_max].",
                  [](NodeSpec& s, TypeDesc t) {
                      s.inputs = {port("x", t, 0.f, "value"), port("in_min", t, 0.f, "input low", -1.f, 0.f),
                                  port("in_max", t, 1.f, "input high", 0.5f, 2.f), port("out_min", t, 0.f, "output low"),
                                  port("out_max", t, 1.f, "output high")};
                      s.outputs = {PortSpec::out("out", t, "remapped value")};
                      s.cpu = byWidth<Remap>(t);
                  });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
