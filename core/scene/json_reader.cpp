// Strict JSON reading with pointer-precise errors.
#include "core/scene/json_reader.h"

#include <sstream>

namespace specula {

std::string jsonTypeName(const Json& j) {
    switch (j.type()) {
        case Json::value_t::null: return "null";
        case Json::value_t::object: return "an object";
        case Json::value_t::array: return "an array";
        case Json::value_t::string: return "a string";
        case Json::value_t::boolean: return "a boolean";
        case Json::value_t::number_integer:
        case Json::value_t::number_unsigned:
        case Json::value_t::number_float: return "a number";
        default: return "an unsupported value";
    }
}

static std::string fmt(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

JsonReader::JsonReader(const Json& j, std::string pointer, std::vector<std::string> allowed)
    : j_(j), ptr_(std::move(pointer)) {
    if (!j_.is_object()) throw InputError(ptr_, "expected an object, got " + jsonTypeName(j_));
    for (auto it = j_.begin(); it != j_.end(); ++it) {
        if (std::find(allowed.begin(), allowed.end(), it.key()) == allowed.end()) {
            std::string valid;
            for (size_t i = 0; i < allowed.size(); ++i) valid += (i ? ", " : "") + allowed[i];
            throw InputError(ptr_ + "/" + pointerEscape(it.key()),
                             "unknown key '" + it.key() + "'; valid keys: " + valid, nearestName(it.key(), allowed));
        }
    }
}

void JsonReader::fail(const std::string& key, const std::string& message, const std::string& suggestion) const {
    throw InputError(key.empty() ? ptr_ : pointer(key), message, suggestion);
}

void JsonReader::require(const std::string& key) const {
    if (!has(key)) throw InputError(ptr_, "missing required key '" + key + "'");
}

float JsonReader::toNumber(const Json& v, const std::string& ptr, float lo, float hi) const {
    if (!v.is_number()) throw InputError(ptr, "expected a number, got " + jsonTypeName(v));
    double d = v.get<double>();
    if (!std::isfinite(d)) throw InputError(ptr, "number is not finite");
    // Compared as the float the scene stores: a documented bound such as 1e12 is itself a rounded float (999999995904),
    // so the double 1e12 would fall just outside it.
    const float f = float(d);
    // The double in the message: a value beyond float's range (1e39) reads as itself, not as "inf".
    if (!(f >= lo && f <= hi))
        throw InputError(ptr, "value " + fmt(std::isfinite(f) ? double(f) : d) + " is outside [" + fmt(lo) + ", " + fmt(hi) + "]");
    return f;
}

float JsonReader::number(const std::string& key, float def, float lo, float hi) const {
    if (!has(key)) return def;
    return toNumber(j_.at(key), pointer(key), lo, hi);
}

float JsonReader::requiredNumber(const std::string& key, float lo, float hi) const {
    require(key);
    return toNumber(j_.at(key), pointer(key), lo, hi);
}

int JsonReader::integer(const std::string& key, int def, int lo, int hi) const {
    if (!has(key)) return def;
    const Json& v = j_.at(key);
    if (!v.is_number()) fail(key, "expected an integer, got " + jsonTypeName(v));
    double d = v.get<double>();
    if (!std::isfinite(d) || d != std::floor(d)) fail(key, "expected an integer, got " + v.dump());
    if (d < lo || d > hi)
        fail(key, "value " + v.dump() + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return int(d);
}

bool JsonReader::boolean(const std::string& key, bool def) const {
    if (!has(key)) return def;
    const Json& v = j_.at(key);
    if (!v.is_boolean()) fail(key, "expected true or false, got " + jsonTypeName(v));
    return v.get<bool>();
}

std::string JsonReader::string(const std::string& key, const std::string& def) const {
    if (!has(key)) return def;
    const Json& v = j_.at(key);
    if (!v.is_string()) fail(key, "expected a string, got " + jsonTypeName(v));
    return v.get<std::string>();
}

std::string JsonReader::requiredString(const std::string& key) const {
    require(key);
    return string(key, "");
}

std::string JsonReader::enumeration(const std::string& key, const std::string& def,
                                    const std::vector<std::string>& options) const {
    std::string s = string(key, def);
    if (std::find(options.begin(), options.end(), s) == options.end()) {
        std::string valid;
        for (size_t i = 0; i < options.size(); ++i) valid += (i ? ", " : "") + options[i];
        fail(key, "unknown value '" + s + "'; expected one of: " + valid, nearestName(s, options));
    }
    return s;
}

Vec3 JsonReader::vec3(const std::string& key, const Vec3& def) const {
    if (!has(key)) return def;
    auto v = numbers(key, 3, {}, -kMaxSceneCoordinate, kMaxSceneCoordinate);
    return {v[0], v[1], v[2]};
}

Vec3 JsonReader::requiredVec3(const std::string& key) const {
    require(key);
    return vec3(key, Vec3(0.f));
}

Color3 JsonReader::color(const std::string& key, const Color3& def) const {
    if (!has(key)) return def;
    auto v = numbers(key, 3, {}, 0.f, kMaxSceneColor);
    return {v[0], v[1], v[2]};
}

std::vector<float> JsonReader::numbers(const std::string& key, size_t n, const std::vector<float>& def, float lo,
                                       float hi) const {
    if (!has(key)) return def;
    const Json& v = j_.at(key);
    if (v.is_number()) return std::vector<float>(n, toNumber(v, pointer(key), lo, hi));
    if (!v.is_array() || v.size() != n)
        fail(key, "expected a number or an array of " + std::to_string(n) + " numbers, got " +
                      (v.is_array() ? "an array of " + std::to_string(v.size()) : jsonTypeName(v)));
    std::vector<float> r(n);
    for (size_t i = 0; i < n; ++i) r[i] = toNumber(v[i], pointer(key) + "/" + std::to_string(i), lo, hi);
    return r;
}

}  // namespace specula
