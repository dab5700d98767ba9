// Out-of-line pieces of the glint BRDF (glint_bsdf.h): the counter of EWA loops stopped by the cell cap.
// Everything else is inline so the node, the tests and the bench share one implementation.
#include "nodes/bsdf/glint/glint_bsdf.h"

namespace specula::glint {

std::atomic<uint64_t>& cellCapHits() {
    static std::atomic<uint64_t> hits{0};
    return hits;
}

}  // namespace specula::glint
