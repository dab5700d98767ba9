// Strict, typed access to one JSON object of a scene file: every read knows its JSON pointer, unknown
// keys are errors with a nearest-name suggestion, numbers must be finite and inside their range.
#pragma once

#include "core/math/math.h"
#include "core/util/error.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace specula {

using Json = nlohmann::json;

// Bounds that keep the renderer's float arithmetic finite (docs/scene-format.md "Value forms", issue 35). A finite
// double such as 3.5e30 still overflows float products: a camera that far away had a squared distance of inf.
// Positions (and every other vector: directions, up, Euler angles, translations) are limited to ±1e8 scene units, and
// so is every world-space vertex after its shape's transform: the largest product the renderer forms from
// coordinates is a cross product's squared length, about 144·x⁴ = 1.4e34 at x = 1e8 (float ends at 3.4e38). Colours
// are limited to 1e6 per component: times the largest strength (power 1e12) that stays below 1e18.
constexpr float kMaxSceneCoordinate = 1e8f;
constexpr float kMaxSceneColor = 1e6f;

std::string jsonTypeName(const Json& j);

class JsonReader {
public:
    // Throws InputError if j is not an object or has a key outside 'allowed'.
    JsonReader(const Json& j, std::string pointer, std::vector<std::string> allowed);

    bool has(const std::string& key) const { return j_.contains(key); }
    const Json& at(const std::string& key) const { return j_.at(key); }
    std::string pointer(const std::string& key) const { return ptr_ + "/" + pointerEscape(key); }
    const std::string& pointer() const { return ptr_; }
    const Json& json() const { return j_; }

    // Required variants throw "missing required key"; optional ones return 'def' when absent.
    float number(const std::string& key, float def, float lo, float hi) const;
    float requiredNumber(const std::string& key, float lo, float hi) const;
    int integer(const std::string& key, int def, int lo, int hi) const;
    bool boolean(const std::string& key, bool def) const;
    std::string string(const std::string& key, const std::string& def) const;
    std::string requiredString(const std::string& key) const;
    // One of 'options' (suggestion on mismatch).
    std::string enumeration(const std::string& key, const std::string& def, const std::vector<std::string>& options) const;
    // Each component in [-kMaxSceneCoordinate, kMaxSceneCoordinate].
    Vec3 vec3(const std::string& key, const Vec3& def) const;
    Vec3 requiredVec3(const std::string& key) const;
    // A colour: [r,g,b] (each in [0, kMaxSceneColor]) or a single number (grey).
    Color3 color(const std::string& key, const Color3& def) const;
    // A number or an array of 'n' numbers.
    std::vector<float> numbers(const std::string& key, size_t n, const std::vector<float>& def, float lo, float hi) const;
    void require(const std::string& key) const;

    [[noreturn]] void fail(const std::string& key, const std::string& message, const std::string& suggestion = "") const;

private:
    float toNumber(const Json& v, const std::string& ptr, float lo, float hi) const;
    const Json& j_;
    std::string ptr_;
};

}  // namespace specula
