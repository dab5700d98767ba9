// The files a command reads, by identity (device, inode and birth time, not by name), so that none of its outputs
// replaces one of them: `glsl --resources DIR` over its own material or texture, `render -o` over a texture.
// Front ends open an InputFileScope for a command; the library's readers note what they open while one is open, and
// every writer of libspecula checks its target first (issue 35, docs/reliability.md "Threat model").
#pragma once

#include <string>
#include <vector>

namespace specula {

// While at least one scope is alive (nesting allowed, from any thread), noteInputFile records the files read; the
// last scope to end forgets them. Hosts that keep a process (Python, Blender) open one per operation.
class InputFileScope {
public:
    InputFileScope();
    ~InputFileScope();
    InputFileScope(const InputFileScope&) = delete;
    InputFileScope& operator=(const InputFileScope&) = delete;
};

// Records 'path' (resolving links) as read by the current command; no-op without a scope or for a missing file.
void noteInputFile(const std::string& path);

// Throws Error(Usage, exit 2) "<option> 'output' is the input file 'input'" when 'output' is (by identity) one
// of 'inputs' or a file noted in the open scope; a missing output never matches. 'option' names the CLI option or
// the API argument ("-o", "--resources", "output").
void refuseOverwritingInputs(const std::string& output, const std::vector<std::string>& inputs, const std::string& option);

// Whether both paths name one file: same device and inode when both exist (links and other spellings included),
// the same normalised path when neither exists yet.
bool sameFile(const std::string& a, const std::string& b);

// The noted files (for messages and tests).
std::vector<std::string> notedInputFiles();

}  // namespace specula
