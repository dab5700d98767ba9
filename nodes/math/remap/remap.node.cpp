// math.remap.<type>: maps x linearly from [in_min, in_max] to [out_min, out_max] (no clamping);
// out_min where in_max == in_min.
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
struct Remap {
    template <int W>
    struct Args {
        FloatN<W> x, inMin, inMax, outMin, outMax;
        static NodeParams<Args> declare(TypeDesc t) {
            return NodeParams<Args>()
                .typed("x", &Args::x, t, 0.f, "value").range(-2.f, 2.f)
                .typed("in_min", &Args::inMin, t, 0.f, "input low").range(-1.f, 0.f)
                .typed("in_max", &Args::inMax, t, 1.f, "input high").range(0.5f, 2.f)
                .typed("out_min", &Args::outMin, t, 0.f, "output low").range(-2.f, 2.f)
                .typed("out_max", &Args::outMax, t, 1.f, "output high").range(-2.f, 2.f);
        }
        FloatN<W> eval() const {
            FloatN<W> o;
            for (int k = 0; k < W; ++k) {
                float d = inMax[k] - inMin[k];
                o[k] = d == 0.f ? outMin[k] : outMin[k] + (x[k] - inMin[k]) / d * (outMax[k] - outMin[k]);
            }
            return o;
        }
    };
};
std::vector<NodeSpec> declare() {
    std::vector<NodeSpec> specs =
        mathNodes<Remap>("remap", mathTypes(), "Linear remap of x from [in_min, in_max] to [out_min, out_max].",
                             "remapped value");
    for (NodeSpec& s : specs)
        s.notes = s.id != "math.remap.float" ? "As `math.remap.float`, per component."
                                             : "out_min + (x − in_min)/(in_max − in_min)·(out_max − out_min); out_min "
                                               "if in_max = in_min; no clamping.";
    return specs;
}
}  // namespace
SPECULA_REGISTER_NODE(declare());
}  // namespace specula::nodes
