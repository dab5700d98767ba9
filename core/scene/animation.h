// Scene animation: keyframed tracks on numbers of the scene document (camera, lights, material literals), addressed by
// JSON pointer and applied to the document before it is read, so that one frame of an animation is an ordinary scene.
#pragma once

#include "core/scene/json_reader.h"

#include <optional>

namespace specula {

struct AnimationRange {
    bool present = false;  // the document has an "animation" block
    int frameStart = 1, frameEnd = 1;
    int frame = 0;  // the frame applied (0 without an animation block)
};

// Reads root["animation"] (docs/scene-format.md "Animation"), evaluates every track at 'frame' (default: frame_start)
// and writes the values into the document at the tracks' targets; removes the block. Throws InputError naming the
// pointer of what is wrong (an unknown target, keys out of order, a value of another shape, a frame outside the range).
AnimationRange applyAnimation(Json& root, std::optional<int> frame);

// The frame range of a scene file's animation without building the scene (farm submit's default --frames).
AnimationRange animationRangeOf(const Json& root);

}  // namespace specula
