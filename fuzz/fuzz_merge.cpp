// libFuzzer target: farm pieces through `specula merge` (core/farm/farm.h mergePieces): EXR files with specula:*
// attributes (frame, frame size, crop, spp, seed, sample block, sample split) and a sample split's 'samples' layer,
// checked, grouped into tiles, summed and written. The first byte picks 1 to 3 pieces; every piece but the last is
// preceded by its length (4 bytes, little endian), the last takes the rest. Only specula::Error may leave; anything
// else or a crash is a finding.
#include "core/farm/farm.h"
#include "core/util/error.h"
#include "fuzz/fuzz_common.h"

#include <cstdio>
#include <cstring>
#include <vector>

using namespace specula;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    static int calls = 0;
    if (++calls % 256 == 0) fuzz::clearScratch();
    const int count = 1 + data[0] % 3;
    size_t pos = 1;
    std::vector<std::string> pieces;
    for (int i = 0; i < count; ++i) {
        size_t length = size - pos;
        if (i + 1 < count) {
            if (size - pos < 4) break;
            uint32_t declared = 0;
            std::memcpy(&declared, data + pos, 4);
            pos += 4;
            length = std::min<size_t>(declared, size - pos);
        }
        // A fresh name per input and piece: nothing is cached by name, but a failed run must not feed the next one.
        pieces.push_back(fuzz::writeScratch("piece" + std::to_string(calls) + "_" + std::to_string(i) + ".exr", data + pos, length));
        pos += length;
    }
    const std::string out = fuzz::scratchDir() + "/merged" + std::to_string(calls) + ".exr";
    try {
        // Pieces capped at 256² pixels, as fuzz_image caps readImageSet: a constant-colour EXR of a few hundred bytes
        // may declare a gigabyte of pixels, legitimately, and would take the campaign's time.
        (void)farm::mergePieces(pieces, out, true, int64_t(fuzz::kFuzzTextureSide) * fuzz::kFuzzTextureSide);
    } catch (const Error&) {
    }
    std::remove(out.c_str());
    return 0;
}
