// Input-error formatting and nearest-name suggestions.
#include "core/util/error.h"

#include <algorithm>
#include <cctype>

namespace specula {

static std::string formatInputError(const std::string& pointer, const std::string& message,
                                    const std::string& suggestion) {
    std::string s = (pointer.empty() ? std::string("/") : pointer) + ": " + message;
    if (!suggestion.empty()) s += " (did you mean '" + suggestion + "'?)";
    return s;
}

InputError::InputError(std::string pointer, std::string message, std::string suggestion)
    : Error(ErrorCode::BadInput, pointer, message, suggestion, formatInputError(pointer, message, suggestion)) {}

const char* errorCodeName(ErrorCode code) {
    switch (code) {
        case ErrorCode::Ok: return "ok";
        case ErrorCode::BadInput: return "bad_input";
        case ErrorCode::Usage: return "usage";
        case ErrorCode::Io: return "io";
        case ErrorCode::Interrupted: return "interrupted";
    }
    return "unknown";
}

static std::string formatError(const std::string& pointer, const std::string& message, const std::string& suggestion) {
    std::string s = pointer.empty() ? message : pointer + ": " + message;
    if (!suggestion.empty()) s += " (did you mean '" + suggestion + "'?)";
    return s;
}

Error::Error(ErrorCode code, std::string pointer, std::string message, std::string suggestion)
    : Error(code, pointer, message, suggestion, formatError(pointer, message, suggestion)) {}

Error::Error(ErrorCode code, std::string pointer, std::string message, std::string suggestion, std::string what)
    : std::runtime_error(what),
      code_(code),
      pointer_(std::move(pointer)),
      message_(std::move(message)),
      suggestion_(std::move(suggestion)) {}

int editDistance(const std::string& a, const std::string& b) {
    std::vector<int> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = int(j);
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = int(i);
        for (size_t j = 1; j <= b.size(); ++j) {
            bool same = std::tolower((unsigned char)a[i - 1]) == std::tolower((unsigned char)b[j - 1]);
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (same ? 0 : 1)});
        }
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

static std::string lower(std::string s) {
    for (auto& c : s) c = char(std::tolower((unsigned char)c));
    return s;
}

std::string nearestName(const std::string& name, const std::vector<std::string>& candidates) {
    if (name.empty()) return "";
    // A prefix relation ("gauss" -> "gaussian", "pointlight" -> "point") is the likeliest intent.
    const std::string ln = lower(name);
    std::string bestPrefix;
    for (const auto& c : candidates) {
        std::string lc = lower(c);
        if (lc == ln) return c;
        bool prefix = (lc.size() >= 3 && ln.rfind(lc, 0) == 0) || (ln.size() >= 3 && lc.rfind(ln, 0) == 0);
        if (prefix && (bestPrefix.empty() || c.size() > bestPrefix.size())) bestPrefix = c;
    }
    if (!bestPrefix.empty()) return bestPrefix;
    std::string best;
    int bestD = 1 << 30;
    for (const auto& c : candidates) {
        int d = editDistance(name, c);
        if (d < bestD) {
            bestD = d;
            best = c;
        }
    }
    int limit = std::max(2, int(name.size()) / 3);
    return bestD <= limit ? best : std::string();
}

std::string pointerEscape(const std::string& key) {
    std::string r;
    for (char c : key) {
        if (c == '~')
            r += "~0";
        else if (c == '/')
            r += "~1";
        else
            r += c;
    }
    return r;
}

}  // namespace specula
