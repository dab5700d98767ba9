// Errors that reach the user: input errors carry the JSON pointer of the offending value and a
// "did you mean" suggestion; each error class maps to one documented CLI exit code.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace specula {

// Documented exit codes of the `specula` CLI (docs/cli.md).
enum ExitCode : int { kExitOk = 0, kExitBadInput = 1, kExitUsage = 2, kExitIo = 3, kExitInterrupted = 130 };

// Bad scene/graph input. what() = "<pointer>: <message>[ (did you mean '<x>'?)]".
class InputError : public std::runtime_error {
public:
    InputError(std::string pointer, std::string message, std::string suggestion = "");
    const std::string& pointer() const { return pointer_; }
    const std::string& message() const { return message_; }
    const std::string& suggestion() const { return suggestion_; }

private:
    std::string pointer_, message_, suggestion_;
};

// File-system / image I/O failure (exit code 3).
class IoError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// Edit distance (Levenshtein, case-insensitive) used for suggestions.
int editDistance(const std::string& a, const std::string& b);
// Closest candidate to 'name' if it is plausibly a typo (distance ≤ max(2, |name|/3)), else "".
std::string nearestName(const std::string& name, const std::vector<std::string>& candidates);
// Escapes a key for use in a JSON pointer (RFC 6901: ~ -> ~0, / -> ~1).
std::string pointerEscape(const std::string& key);

}  // namespace specula
