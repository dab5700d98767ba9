// Out-of-line piece of the glint cell set (glint_cells.h): the counter of EWA loops stopped by the cell cap, shared by
// every thread so tests and the renderer can report how often the GLSL's cap of kCellCap cells per LOD was reached.
#include "nodes/bsdf/glint/glint_cells.h"

namespace specula::glint {

std::atomic<uint64_t>& cellCapHits() {
    static std::atomic<uint64_t> hits{0};
    return hits;
}

}  // namespace specula::glint
