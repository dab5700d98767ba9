// Memory budget (core/util/memory_budget.h): Linux's limits, read from /proc, /sys/fs/cgroup and getrlimit.
#include "core/util/memory_budget.h"

#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace specula {

namespace {

uint64_t pageBytes() { return uint64_t(sysconf(_SC_PAGESIZE)); }

// Field 'index' (0: size, 1: resident) of /proc/self/statm, in bytes.
uint64_t statmBytes(int index) {
    std::ifstream in("/proc/self/statm");
    uint64_t v[2] = {0, 0};
    in >> v[0] >> v[1];
    return v[index] * pageBytes();
}

bool readNumber(const std::string& path, uint64_t& value) {
    std::ifstream in(path);
    std::string word;
    if (!(in >> word) || word == "max") return false;
    try {
        value = std::stoull(word);
        return true;
    } catch (...) {
        return false;
    }
}

void tighten(MemoryBudget& b, uint64_t limit, uint64_t used, const std::string& what) {
    uint64_t left = limit > used ? limit - used : 0;
    if (left < b.availableBytes) {
        b.availableBytes = left;
        b.limitedBy = what + " of " + formatBytes(limit);
    }
}

}  // namespace

MemoryBudget memoryBudget(uint64_t maxMemoryBytes) {
    MemoryBudget b;
    if (maxMemoryBytes) tighten(b, maxMemoryBytes, statmBytes(1), "--max-memory");
    rlimit as{};
    if (getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY)
        tighten(b, uint64_t(as.rlim_cur), statmBytes(0), "the address-space limit (ulimit -v)");
    uint64_t cgMax = 0, cgCurrent = 0;
    if (readNumber("/sys/fs/cgroup/memory.max", cgMax) && readNumber("/sys/fs/cgroup/memory.current", cgCurrent))
        tighten(b, cgMax, cgCurrent, "the cgroup's memory.max");
    std::ifstream meminfo("/proc/meminfo");
    for (std::string line; std::getline(meminfo, line);) {
        uint64_t kib = 0;
        if (std::sscanf(line.c_str(), "MemAvailable: %lu kB", &kib) == 1) {
            if (kib * 1024 < b.availableBytes) {
                b.availableBytes = kib * 1024;
                b.limitedBy = "the available physical memory";
            }
            break;
        }
    }
    return b;
}

bool parseByteSize(const std::string& text, uint64_t& bytes) {
    std::istringstream in(text);
    double v = 0;
    if (!(in >> v) || !(v > 0) || !std::isfinite(v)) return false;
    std::string unit;
    in >> unit;
    if (!in.eof() && !(in >> std::ws).eof()) return false;
    double scale = 1;
    if (unit.empty() || unit == "B") scale = 1;
    else if (unit == "K" || unit == "KiB") scale = 1024.0;
    else if (unit == "M" || unit == "MiB") scale = 1024.0 * 1024;
    else if (unit == "G" || unit == "GiB") scale = 1024.0 * 1024 * 1024;
    else if (unit == "T" || unit == "TiB") scale = 1024.0 * 1024 * 1024 * 1024;
    else return false;
    double total = v * scale;
    if (!(total >= 1) || total > 1.8e19) return false;
    bytes = uint64_t(total);
    return true;
}

std::string formatBytes(uint64_t bytes) {
    const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB"};
    double v = double(bytes);
    int u = 0;
    while (v >= 1024 && u < 4) v /= 1024, ++u;
    char buf[48];
    if (u == 0) std::snprintf(buf, sizeof buf, "%llu bytes", (unsigned long long)bytes);
    else std::snprintf(buf, sizeof buf, "%.1f %s", v, units[u]);
    return buf;
}

}  // namespace specula
