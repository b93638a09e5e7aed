/// @file pages.h
/// @brief Large buffers with their pages faulted in by one call. The first write to each 4 KiB
/// page of a fresh allocation is a page fault. On virtual machines a fault is dear: on the
/// Firecracker machines this project is measured on, touching 150 MB a page at a time took
/// 0.49 s, and the same after the kernel populated the range in one call (MADV_POPULATE_WRITE,
/// Linux 5.14 and later) 0.15 s in all. Elsewhere the call is skipped or fails harmlessly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace dexelmill::detail {

/// Below this the faults are too few to matter.
constexpr std::size_t kPopulateBytes = std::size_t(4) << 20;

/// @brief Reserves room for n elements and, for a large buffer, has the kernel fault its pages in
/// at once, so that the resize or the writes that follow do not fault page by page.
template <class T, class A>
void reservePopulated(std::vector<T, A>& v, std::size_t n) {
    v.reserve(n);
#if defined(__linux__) && defined(MADV_POPULATE_WRITE)
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kPopulateBytes) return;
    const auto page = std::uintptr_t(sysconf(_SC_PAGESIZE));
    const auto first = (reinterpret_cast<std::uintptr_t>(v.data()) + page - 1) & ~(page - 1);
    const auto last = (reinterpret_cast<std::uintptr_t>(v.data()) + bytes) & ~(page - 1);
    // Failure (an older kernel, no memory to populate now) only means the faults come later.
    if (last > first) (void)madvise(reinterpret_cast<void*>(first), last - first, MADV_POPULATE_WRITE);
#endif
}

}  // namespace dexelmill::detail
