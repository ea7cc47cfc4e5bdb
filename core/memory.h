// How much memory this process may still use, so that a run too large for the machine is
// refused before it starts instead of ending in std::bad_alloc (or the OOM killer).
#pragma once

#include <sys/resource.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "core/error.h"

namespace reliefsim {

namespace detail {

/// The first number in a file such as /sys/fs/cgroup/memory.max ("max" -> nothing).
inline bool ReadFirstNumber(const char* path, uint64_t& value) {
    std::ifstream f(path);
    std::string word;
    if (!(f >> word) || word.empty() || word[0] < '0' || word[0] > '9') return false;
    value = std::stoull(word);
    return true;
}

/// MemAvailable of /proc/meminfo, in bytes.
inline bool ReadMemAvailable(uint64_t& bytes) {
    std::ifstream f("/proc/meminfo");
    std::string key, unit;
    uint64_t kb = 0;
    while (f >> key >> kb) {
        std::getline(f, unit);
        if (key == "MemAvailable:") {
            bytes = kb * 1024;
            return true;
        }
    }
    return false;
}

}  // namespace detail

/// RELIEFSIM_MEMORY_LIMIT (bytes, or with a K, M or G suffix: "512M"), when set: a cap
/// the user (or a fuzzer, whose allocation limit the kernel does not know of) puts on a
/// run.
inline bool ReadMemoryLimitEnv(uint64_t& bytes) {
    const char* text = std::getenv("RELIEFSIM_MEMORY_LIMIT");
    if (!text || !*text) return false;
    char* end = nullptr;
    const unsigned long long v = std::strtoull(text, &end, 10);
    if (end == text) return false;
    uint64_t scale = 1;
    if (*end == 'K' || *end == 'k')
        scale = 1ull << 10;
    else if (*end == 'M' || *end == 'm')
        scale = 1ull << 20;
    else if (*end == 'G' || *end == 'g')
        scale = 1ull << 30;
    else if (*end != '\0')
        return false;
    bytes = uint64_t(v) * scale;
    return true;
}

/// Bytes this process can still allocate: the smallest of RELIEFSIM_MEMORY_LIMIT, the
/// kernel's MemAvailable, the cgroup's limit minus its usage (v2 memory.max /
/// memory.current, or v1), and the address- space and data-segment limits (RLIMIT_AS,
/// RLIMIT_DATA, e.g. from `ulimit -v`). A source that cannot be read does not limit; with
/// none readable the answer is UINT64_MAX.
inline uint64_t AvailableMemoryBytes() {
    uint64_t best = UINT64_MAX, v = 0, used = 0;
    if (ReadMemoryLimitEnv(v)) best = v;
    if (detail::ReadMemAvailable(v)) best = std::min(best, v);
    if (detail::ReadFirstNumber("/sys/fs/cgroup/memory.max", v)) {
        detail::ReadFirstNumber("/sys/fs/cgroup/memory.current", used);
        best = std::min(best, v > used ? v - used : 0);
    } else if (detail::ReadFirstNumber("/sys/fs/cgroup/memory/memory.limit_in_bytes",
                                       v) &&
               v < (uint64_t(1) << 60)) {
        used = 0;
        detail::ReadFirstNumber("/sys/fs/cgroup/memory/memory.usage_in_bytes", used);
        best = std::min(best, v > used ? v - used : 0);
    }
    for (int resource : {RLIMIT_AS, RLIMIT_DATA}) {
        rlimit r{};
        if (getrlimit(resource, &r) == 0 && r.rlim_cur != RLIM_INFINITY)
            best = std::min(best, uint64_t(r.rlim_cur));
    }
    return best;
}

/// "1.5 GiB", "300 MiB", "12 KiB", "512 B".
inline std::string FormatBytes(uint64_t bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB"};
    double v = double(bytes);
    int u = 0;
    while (v >= 1024.0 && u < 5) {
        v /= 1024.0;
        ++u;
    }
    char buf[32];
    if (u == 0)
        std::snprintf(buf, sizeof buf, "%llu B", static_cast<unsigned long long>(bytes));
    else
        std::snprintf(buf, sizeof buf, "%.1f %s", v, units[u]);
    return buf;
}

/// Throws Error "SUBJECT: needs about N of memory, M available; HINT" when `bytes`
/// exceeds what AvailableMemoryBytes() reports (leaving a 5% margin for everything else).
inline void RequireMemory(uint64_t bytes, const std::string& subject,
                          const std::string& hint) {
    const uint64_t avail = AvailableMemoryBytes();
    if (avail == UINT64_MAX) return;
    if (double(bytes) > 0.95 * double(avail))
        throw Error(subject + ": needs about " + FormatBytes(bytes) + " of memory, " +
                    FormatBytes(avail) + " available; " + hint);
}

/// For loops that allocate and free the same large buffers every iteration (`render
/// --animate`, `maps --animate`, their benchmarks): keeps freed memory in the heap.
/// glibc otherwise returns blocks above its mmap threshold to the system, and every
/// iteration faults them in again (measured: 5-30 ms of a 13 ms animated frame here).
inline void KeepFreedMemoryInHeap() {
#if defined(__GLIBC__)
    mallopt(M_MMAP_THRESHOLD, 1 << 30);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

}  // namespace reliefsim
