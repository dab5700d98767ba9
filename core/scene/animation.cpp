// Keyframe evaluation for scene animation (core/scene/animation.h): linear, constant (step) and smooth (ease in and
// out: smoothstep of the linear parameter) interpolation between keys; before the first and after the last key a track
// holds its end value, as Blender's F-curves with constant extrapolation do.
#include "core/scene/animation.h"

#include "core/util/error.h"

#include <cmath>

namespace specula {

namespace {

constexpr int kMaxFrame = 1000000;

AnimationRange readRange(const Json& anim) {
    JsonReader r(anim, "/animation", {"frame_start", "frame_end", "fps", "tracks"});
    AnimationRange range;
    range.present = true;
    range.frameStart = r.integer("frame_start", 1, -kMaxFrame, kMaxFrame);
    range.frameEnd = r.integer("frame_end", range.frameStart, -kMaxFrame, kMaxFrame);
    r.number("fps", 24.f, 1e-3f, 1e6f);  // for hosts and players; frames are what the renderer counts
    if (range.frameEnd < range.frameStart)
        r.fail("frame_end", "frame_end " + std::to_string(range.frameEnd) + " is before frame_start " +
                                std::to_string(range.frameStart));
    return range;
}

// The shape of an animatable value: a number (-1) or an array of that many numbers.
int shapeOf(const Json& v) {
    if (v.is_number()) return -1;
    if (!v.is_array() || v.empty()) return -2;
    for (const Json& e : v)
        if (!e.is_number()) return -2;
    return int(v.size());
}

std::string describeShape(int shape) { return shape == -1 ? "a number" : "an array of " + std::to_string(shape) + " numbers"; }

double ease(const std::string& interpolation, double t) {
    if (interpolation == "constant") return 0.0;
    if (interpolation == "smooth") return t * t * (3.0 - 2.0 * t);
    return t;
}

}  // namespace

AnimationRange animationRangeOf(const Json& root) {
    if (!root.is_object() || !root.contains("animation")) return {};
    return readRange(root.at("animation"));
}

AnimationRange applyAnimation(Json& root, std::optional<int> frame) {
    if (!root.is_object() || !root.contains("animation")) {
        if (frame && *frame != 0 && *frame != 1)
            throw InputError("--frame", "frame " + std::to_string(*frame) + " asks for a frame of a scene without an \"animation\" block");
        return {};
    }
    const Json anim = root.at("animation");  // a copy: the targets are written into root
    AnimationRange range = readRange(anim);
    range.frame = frame.value_or(range.frameStart);
    if (range.frame < range.frameStart || range.frame > range.frameEnd)
        throw InputError("/animation/frame_end", "frame " + std::to_string(range.frame) + " is outside the animation's frames " +
                                                     std::to_string(range.frameStart) + "-" + std::to_string(range.frameEnd));
    root.erase("animation");
    if (!anim.contains("tracks")) return range;
    const Json& tracks = anim.at("tracks");
    if (!tracks.is_array()) throw InputError("/animation/tracks", "expected an array of tracks, got " + jsonTypeName(tracks));
    for (size_t i = 0; i < tracks.size(); ++i) {
        const std::string tp = "/animation/tracks/" + std::to_string(i);
        JsonReader tr(tracks[i], tp, {"target", "keys", "interpolation"});
        const std::string target = tr.requiredString("target");
        const std::string interpolation = tr.enumeration("interpolation", "linear", {"linear", "constant", "smooth"});
        Json::json_pointer ptr;
        try {
            ptr = Json::json_pointer(target);
        } catch (const Json::exception&) {
            tr.fail("target", "'" + target + "' is not a JSON pointer (it starts with '/', e.g. /camera/position)");
        }
        if (target.empty() || target.rfind("/animation", 0) == 0) tr.fail("target", "a track cannot animate '" + target + "'");
        if (!root.contains(ptr)) {
            // Name the deepest part of the path that exists, and the nearest key there.
            Json::json_pointer parent = ptr.parent_pointer();
            while (!parent.empty() && !root.contains(parent)) parent = parent.parent_pointer();
            const Json& at = root.at(parent);
            std::string suggestion;
            if (at.is_object()) {
                std::vector<std::string> keys;
                for (auto it = at.begin(); it != at.end(); ++it) keys.push_back(it.key());
                const std::string missing = target.substr(parent.to_string().size() + 1);
                suggestion = nearestName(missing.substr(0, missing.find('/')), keys);
            }
            tr.fail("target", "target '" + target + "' is not in the scene (a track changes a value the scene already has)",
                    suggestion);
        }
        Json& value = root.at(ptr);
        const int shape = shapeOf(value);
        if (shape < -1) tr.fail("target", "target '" + target + "' holds " + jsonTypeName(value) + "; tracks animate numbers and arrays of numbers");
        tr.require("keys");
        const Json& keys = tr.at("keys");
        if (!keys.is_array() || keys.empty())
            throw InputError(tp + "/keys", "expected a non-empty array of keys {\"frame\": F, \"value\": V}");
        std::vector<int> frames;
        std::vector<const Json*> values;
        for (size_t k = 0; k < keys.size(); ++k) {
            const std::string kp = tp + "/keys/" + std::to_string(k);
            JsonReader kr(keys[k], kp, {"frame", "value"});
            kr.require("frame");
            kr.require("value");
            const int f = kr.integer("frame", 0, -kMaxFrame, kMaxFrame);
            if (!frames.empty() && f <= frames.back())
                kr.fail("frame", "key frames must increase (frame " + std::to_string(f) + " follows " + std::to_string(frames.back()) + ")");
            const Json& v = kr.at("value");
            if (shapeOf(v) != shape)
                kr.fail("value", "the target holds " + describeShape(shape) + ", this key " +
                                     (shapeOf(v) < -1 ? "holds " + jsonTypeName(v) : "is " + describeShape(shapeOf(v))));
            for (const Json& e : (shape == -1 ? Json::array({v}) : v))
                if (!std::isfinite(e.get<double>())) kr.fail("value", "key values must be finite");
            frames.push_back(f);
            values.push_back(&v);
        }
        // The segment holding the frame; before the first and after the last key the end value holds.
        size_t k1 = 0;
        while (k1 < frames.size() && frames[k1] < range.frame) ++k1;
        if (k1 == frames.size()) {
            value = *values.back();
        } else if (k1 == 0 || frames[k1] == range.frame) {
            value = *values[k1];
        } else {
            const size_t k0 = k1 - 1;
            const double t = ease(interpolation, double(range.frame - frames[k0]) / double(frames[k1] - frames[k0]));
            auto mix = [t](const Json& a, const Json& b) { return a.get<double>() + (b.get<double>() - a.get<double>()) * t; };
            if (shape == -1) {
                value = mix(*values[k0], *values[k1]);
            } else {
                for (int c = 0; c < shape; ++c) value[size_t(c)] = mix((*values[k0])[size_t(c)], (*values[k1])[size_t(c)]);
            }
        }
    }
    return range;
}

}  // namespace specula
