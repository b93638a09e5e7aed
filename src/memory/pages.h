/// @file pages.h
/// @brief Large buffers whose pages come cheaply. The first write to each 4 KiB page of a fresh
/// allocation is a page fault, and on virtual machines a fault is dear: on the Firecracker
/// machines this project is measured on, touching 150 MB a page at a time took 0.49 s, and the
/// same after the kernel populated the range in one call (MADV_POPULATE_WRITE, Linux 5.14 and
/// later) 0.15 s in all. Where the kernel gives transparent huge pages on advice (MADV_HUGEPAGE),
/// a buffer is advised instead: its faults come 2 MiB at a time, 512 times fewer, and reads
/// scattered over it miss the TLB far less. On the hood at 1 mm (runs in turn with the populating
/// build, medians of three) the STL's write, which reads the 0.35 GB vertex list (14.6 million
/// vertices) in triangle order, took 2.7 s instead of 5.2 s on two threads and 2.8 s instead of
/// 4.4 s on one; the mesh stage moved within the machine's noise. Advising and then populating
/// made the mesh stage slower (3.65 s against 2.81 s on two threads). Elsewhere the calls are
/// skipped or fail harmlessly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace dexelmill::detail {

/// Below this the faults are too few to matter.
constexpr std::size_t kPopulateBytes = std::size_t(4) << 20;

/// The kernel's transparent huge page mode, the bracketed word of its setting: "always",
/// "madvise" or "never"; empty where the setting does not exist.
inline const std::string& hugePageMode() {
    static const std::string mode = [] {
        std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
        std::string line;
        std::getline(in, line);
        const std::size_t open = line.find('['), close = line.find(']');
        return open != std::string::npos && close != std::string::npos && close > open
                   ? line.substr(open + 1, close - open - 1)
                   : std::string();
    }();
    return mode;
}

/// Whether memory advised with MADV_HUGEPAGE gets transparent huge pages: the kernel's mode is
/// "always" or "madvise" (not "never", and the setting exists).
inline bool hugePagesOnAdvice() { return hugePageMode() == "always" || hugePageMode() == "madvise"; }

/// @brief Reserves room for n elements and, for a large buffer, makes its pages cheap to fault
/// in: advised for huge pages where the kernel gives them, else faulted in by the kernel at once,
/// so that the resize or the writes that follow do not fault page by page.
template <class T, class A>
void reservePopulated(std::vector<T, A>& v, std::size_t n) {
    v.reserve(n);
#if defined(__linux__) && (defined(MADV_HUGEPAGE) || defined(MADV_POPULATE_WRITE))
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kPopulateBytes) return;
    const auto page = std::uintptr_t(sysconf(_SC_PAGESIZE));
    const auto first = (reinterpret_cast<std::uintptr_t>(v.data()) + page - 1) & ~(page - 1);
    const auto last = (reinterpret_cast<std::uintptr_t>(v.data()) + bytes) & ~(page - 1);
    if (last <= first) return;
    void* const start = reinterpret_cast<void*>(first);
#if defined(MADV_HUGEPAGE)
    if (hugePagesOnAdvice() && madvise(start, last - first, MADV_HUGEPAGE) == 0) return;
#endif
#if defined(MADV_POPULATE_WRITE)
    // Failure (an older kernel, no memory to populate now) only means the faults come later.
    (void)madvise(start, last - first, MADV_POPULATE_WRITE);
#endif
#endif
}

}  // namespace dexelmill::detail
