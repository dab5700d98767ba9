// Memory budget of a render: how many bytes this process may still allocate (the address-space limit, the cgroup's
// limit, available physical memory, or a limit the user sets), so a render too large fails with a clear error first.
#pragma once

#include <cstdint>
#include <string>

namespace specula {

struct MemoryBudget {
    uint64_t availableBytes = UINT64_MAX;  // what may still be allocated
    std::string limitedBy;                 // which limit gave it, for messages ("--max-memory of 4.0 GiB", ...)
};

// The tightest of: maxMemoryBytes (if non-zero) less the resident set; the soft RLIMIT_AS less the virtual size; the
// cgroup v2 memory.max less memory.current; /proc/meminfo's MemAvailable.
MemoryBudget memoryBudget(uint64_t maxMemoryBytes = 0);

// "4G", "512M", "1.5G", "1000000000" (bytes); K/M/G/T are powers of 1024. Returns false for anything else or zero.
bool parseByteSize(const std::string& text, uint64_t& bytes);

// 3.2 GiB, 512.0 MiB, ...
std::string formatBytes(uint64_t bytes);

}  // namespace specula
