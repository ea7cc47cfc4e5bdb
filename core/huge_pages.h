// Large buffers on transparent huge pages. The first touch of fresh memory costs one page
// fault per 4 KiB page, and on virtual machines a fault is expensive: about 3 ms per MiB
// measured on the project's 2-core VM (16 MiB in 44-60 ms), against about 0.1 ms per MiB
// on 2 MiB pages. Where the kernel lends huge pages only on request
// (/sys/kernel/mm/transparent_hugepage/enabled = madvise, Debian's default), a buffer of
// several MiB asks for them before it is first written: AssignOnHugePages reserves the
// vector's storage, advises it (MADV_HUGEPAGE) and only then fills it. A hint: where the
// kernel declines, nothing changes but the time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace reliefsim {

/// Asks for huge pages on the whole 4 KiB pages of [p, p + bytes), for buffers of at
/// least 2 MiB (smaller ones could not hold a huge page); not yet touched pages only.
inline void AdviseHugePages(void* p, size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    constexpr uintptr_t kPage = 4096, kHuge = uintptr_t(2) << 20;
    if (bytes < kHuge) return;
    const uintptr_t begin = (reinterpret_cast<uintptr_t>(p) + kPage - 1) & ~(kPage - 1);
    const uintptr_t end = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(kPage - 1);
    if (end > begin)
        static_cast<void>(madvise(reinterpret_cast<void*>(begin), end - begin,
                                  MADV_HUGEPAGE));  // a hint: failure changes nothing
#else
    static_cast<void>(p);
    static_cast<void>(bytes);
#endif
}

/// v.assign(n, value), with fresh storage of several MiB on huge pages (AdviseHugePages).
template <class T>
void AssignOnHugePages(std::vector<T>& v, size_t n, const T& value = T()) {
    if (v.capacity() < n) {
        std::vector<T>().swap(v);  // the old storage first: no two buffers at once
        v.reserve(n);
        AdviseHugePages(v.data(), n * sizeof(T));
    }
    v.assign(n, value);
}

/// v.resize(n) (values kept, new ones value-initialised), the same way.
template <class T>
void ResizeOnHugePages(std::vector<T>& v, size_t n) {
    if (v.capacity() < n) {
        std::vector<T> fresh;
        fresh.reserve(n);
        AdviseHugePages(fresh.data(), n * sizeof(T));
        fresh.assign(v.begin(), v.end());
        v.swap(fresh);
    }
    v.resize(n);
}

}  // namespace reliefsim
