// Where the normal-map nodes get their texels: a file read through the texture store as raw data, or a procedural
// map named 'generate:<kind>:<size>:<seed>' (core/texture/normal_map_gen.h), decoded and checked once at prepare.
#pragma once

#include "core/util/error.h"

#include "core/graph/node_spec.h"
#include "core/math/math.h"

#include <string>
#include <vector>

namespace specula::nodes {

// A tangent-space normal map as prepare steps need it: the encoded texels (colour = (n + 1)/2, rows top to bottom as
// the file stores them, for GPU resources such as the LEAN pyramid) and the decoded normals with row 0 = v = 0 (the
// bottom row), OpenGL convention (+y = +v) after the DirectX flip.
struct NormalMapSource {
    int width = 0, height = 0, channels = 0;
    std::vector<float> encoded;  // width x height x channels
    std::vector<Vec3> normals;   // width x height, bottom-up
    std::string name;            // the file as written in the material (for messages)
};

// A texture input's path as the texture store should open it: relative paths against the scene file's folder;
// absolute paths and generated maps ('generate:<kind>:<size>:<seed>', core/texture/normal_map_gen.h) unchanged.
std::string resolveTexturePath(const graph::PrepareContext& pc, const std::string& file);

// The error of a texture that did not load (cause), at the JSON pointer 'pointer': a missing file or one beyond the
// limits (TextureInputError) is an InputError (exit 1), a file that exists but cannot be read or decoded is an I/O error
// (exit 3, docs/cli.md), as for meshes.
[[noreturn]] void throwTextureLoadError(const std::string& pointer, const std::string& path, const std::string& message,
                                        const std::exception& cause);

struct NormalMapChecks {
    // Reject maps whose decoded vectors are not unit length (a colour image or a height map given by mistake): more
    // than maxBadFraction of the texels off by more than lengthTolerance. 8-bit quantisation alone stays below 0.01.
    bool requireUnitLength = false;
    float lengthTolerance = 0.1f;
    float maxBadFraction = 0.01f;
    // Normalise every decoded vector (after the check).
    bool normalise = false;
};

// Reads the normal map named by the string input 'port' of the node being prepared (a file or a generated map). Every failure is an InputError
// at the port's JSON pointer naming the file: no texture store, unreadable file, a channel count other than 2 (RG,
// z reconstructed), 3 or 4, and the unit-length check. 'node' is the node type for the messages.
NormalMapSource loadNormalMapSource(const graph::PrepareContext& pc, const std::string& port, const char* node,
                                    bool directx, const NormalMapChecks& checks = {});

}  // namespace specula::nodes
