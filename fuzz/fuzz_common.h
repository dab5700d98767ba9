// Shared pieces of the libFuzzer targets (fuzz/README in docs/reliability.md): a private scratch folder per process,
// the one shading point every graph is run at, and the rule that only documented errors may leave a target.
#pragma once

#include "core/render/shading.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

namespace specula::fuzz {

// The texture side cap of the scene and graph targets (a host's SceneLimits::maxTextureSide): every texture the seeds
// use fits (make_corpus.py shrinks generated maps to 64), and the refusal above it is a path worth fuzzing.
constexpr int kFuzzTextureSide = 256;

// A folder of this process's own under $TMPDIR (made once, emptied by clearScratch), for files the loaders read.
// Caches (glint dictionaries, P-NDFs, LTC prefilters) go to $SPECULA_CACHE_DIR, which fuzz/run.sh keeps in the build
// folder so that seeds do not rebuild them at every run.
const std::string& scratchDir();
void clearScratch();
// Writes bytes to scratchDir()/name and returns the path.
std::string writeScratch(const std::string& name, const uint8_t* data, size_t size);

// The input as JSON; false for text the JSON parser rejects (not a finding: the parser is not ours).
bool parseJson(const uint8_t* data, size_t size, nlohmann::json& out);

// The scene targets' end: 'load' with a 16x12, 1-spp override and textures capped at kFuzzTextureSide (a mutant
// asking for a 1024² P-NDF or LTC prefilter, over 60 s under ASan, takes the refusal path instead of stalling the
// campaign), then a one-thread render of what loads; specula::Error is the documented way out and is swallowed.
void loadAndRenderTiny(const std::function<Scene(const SceneOverrides&)>& load);

// A shading point with differentials, as a camera ray at a unit sphere would give.
ShadingPoint fuzzShadingPoint();

}  // namespace specula::fuzz
