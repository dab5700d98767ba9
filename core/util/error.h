// Errors that reach the user: input errors carry the JSON pointer of the offending value and a
// "did you mean" suggestion; each error class maps to one documented CLI exit code.
#pragma once

#include "specula/error.h"

#include <stdexcept>
#include <string>
#include <vector>

namespace specula {

// Documented exit codes of the `specula` CLI (docs/cli.md).
enum ExitCode : int { kExitOk = 0, kExitBadInput = 1, kExitUsage = 2, kExitIo = 3, kExitInterrupted = 130 };

// Bad scene/graph input (ErrorCode::BadInput). what() = "<pointer>: <message>[ (did you mean '<x>'?)]"
// ("/" for an empty pointer).
class InputError : public Error {
public:
    InputError(std::string pointer, std::string message, std::string suggestion = "");
};

// File-system / image I/O failure (exit code 3, ErrorCode::Io).
class IoError : public Error {
public:
    explicit IoError(const std::string& message) : Error(ErrorCode::Io, "", message) {}
};

// Edit distance (Levenshtein, case-insensitive) used for suggestions.
int editDistance(const std::string& a, const std::string& b);
// Closest candidate to 'name' if it is plausibly a typo (distance ≤ max(2, |name|/3)), else "".
std::string nearestName(const std::string& name, const std::vector<std::string>& candidates);
// Escapes a key for use in a JSON pointer (RFC 6901: ~ -> ~0, / -> ~1).
std::string pointerEscape(const std::string& key);

}  // namespace specula
