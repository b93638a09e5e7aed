#include "memory/pages.h"

#include <new>

#include "dexelmill/surface/mesh.h"

namespace dexelmill::detail {

namespace {

/// Transparent huge pages are this large on x86-64 and the usual arm64 kernels; where they are
/// larger, advice still gives huge pages to the 2 MiB runs that line up with them.
constexpr std::size_t kHugePage = std::size_t(2) << 20;

/// Lists from this size on get a mapping of their own: a huge page's first write costs less than
/// the 256 small pages of a list this size would, and what it leaves unused is at most as large.
constexpr std::size_t kOwnMappingBytes = std::size_t(1) << 20;

/// Whether a list of this size gets a mapping of its own.
bool ownMapping(std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    return bytes >= kOwnMappingBytes && hugePagesOnAdvice();
#else
    (void)bytes;
    return false;
#endif
}

std::size_t roundUp(std::size_t bytes) { return (bytes + kHugePage - 1) & ~(kHugePage - 1); }

}  // namespace

void* allocateList(std::size_t bytes) {
    if (!ownMapping(bytes)) return ::operator new(bytes);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    // Map a huge page more than needed, keep the aligned run and return the rest at once.
    const std::size_t size = roundUp(bytes);
    void* raw = mmap(nullptr, size + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (raw == MAP_FAILED) throw std::bad_alloc();
    const auto base = reinterpret_cast<std::uintptr_t>(raw);
    const std::uintptr_t start = (base + kHugePage - 1) & ~std::uintptr_t(kHugePage - 1);
    if (start > base) munmap(raw, start - base);
    munmap(reinterpret_cast<void*>(start + size), base + kHugePage - start);  // never empty: start < base + kHugePage
    // Failure only means small pages.
    (void)madvise(reinterpret_cast<void*>(start), size, MADV_HUGEPAGE);
    return reinterpret_cast<void*>(start);
#else
    return ::operator new(bytes);
#endif
}

void deallocateList(void* p, std::size_t bytes) noexcept {
    if (!ownMapping(bytes)) {
        ::operator delete(p);
        return;
    }
#if defined(__linux__)
    munmap(p, roundUp(bytes));
#endif
}

}  // namespace dexelmill::detail
