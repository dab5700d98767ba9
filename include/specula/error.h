// libspecula's one error type: a code (the `specula` CLI's exit code), the JSON pointer of the offending
// value (empty when none), the message and a "did you mean" suggestion (empty when none).
#pragma once

#include <stdexcept>
#include <string>

namespace specula {

// The documented exit codes of the `specula` CLI (docs/cli.md); every Error maps to one.
enum class ErrorCode : int { Ok = 0, BadInput = 1, Usage = 2, Io = 3, Interrupted = 130 };

// "ok", "bad_input", "usage", "io", "interrupted".
const char* errorCodeName(ErrorCode code);

class Error : public std::runtime_error {
public:
    // what() = "<pointer>: <message>[ (did you mean '<suggestion>'?)]" when there is a pointer, else
    // "<message>[ (did you mean '<suggestion>'?)]".
    Error(ErrorCode code, std::string pointer, std::string message, std::string suggestion = "");
    ErrorCode code() const { return code_; }
    int exitCode() const { return int(code_); }
    const std::string& pointer() const { return pointer_; }
    const std::string& message() const { return message_; }
    const std::string& suggestion() const { return suggestion_; }

protected:
    Error(ErrorCode code, std::string pointer, std::string message, std::string suggestion, std::string what);

private:
    ErrorCode code_;
    std::string pointer_, message_, suggestion_;
};

}  // namespace specula
