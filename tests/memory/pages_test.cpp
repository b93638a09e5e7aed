// Large buffers' pages: the advice reservePopulated gives shows in the kernel's own record of the
// mapping (/proc/self/smaps), read here without the code under test.
#include <catch2/catch.hpp>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "dexelmill/surface/mesh.h"
#include "memory/pages.h"

namespace {

/// The VmFlags line of the mapping holding address p in /proc/self/smaps; empty if none is found.
std::string vmFlagsAt(const void* p) {
    std::ifstream in("/proc/self/smaps");
    const auto at = reinterpret_cast<std::uintptr_t>(p);
    std::string line;
    bool inside = false;
    while (std::getline(in, line)) {
        std::uintptr_t lo = 0, hi = 0;
        char dash = 0;
        std::istringstream head(line);
        if (head >> std::hex >> lo >> dash >> hi && dash == '-') {
            inside = lo <= at && at < hi;
            continue;
        }
        if (inside && line.rfind("VmFlags:", 0) == 0) return line;
    }
    return {};
}

bool hasFlag(const std::string& flags, const std::string& flag) {
    std::istringstream words(flags);
    std::string w;
    while (words >> w)
        if (w == flag) return true;
    return false;
}

}  // namespace

TEST_CASE("pages: a large buffer is advised for huge pages where the kernel gives them", "[memory]") {
    std::vector<double> big;
    const std::size_t n = 4 * dexelmill::detail::kPopulateBytes / sizeof(double);
    dexelmill::detail::reservePopulated(big, n);
    REQUIRE(big.capacity() >= n);
    big.assign(n, 1.5);
    CHECK(big[n / 2] == 1.5);

    const std::string flags = vmFlagsAt(big.data() + n / 2);
    if (flags.empty()) {
        WARN("no /proc/self/smaps entry for the buffer: the advice is not checked");
        return;
    }
    // "hg": the mapping was advised MADV_HUGEPAGE (the kernel's VM_HUGEPAGE).
    CHECK(hasFlag(flags, "hg") == dexelmill::detail::hugePagesOnAdvice());
}

TEST_CASE("pages: a small buffer is only reserved", "[memory]") {
    std::vector<char> small;
    dexelmill::detail::reservePopulated(small, 1000);
    CHECK(small.capacity() >= 1000);
    CHECK(small.empty());
}

TEST_CASE("pages: a large list's memory is a mapping of its own, aligned for huge pages", "[memory]") {
    using List = std::vector<std::uint32_t, dexelmill::NoZeroAllocator<std::uint32_t>>;
    List big(std::size_t(3) << 20);  // 12 MB
    for (std::size_t i = 0; i < big.size(); i += 1024) big[i] = std::uint32_t(i);
    CHECK(big[5 * 1024] == 5 * 1024);
    const auto at = reinterpret_cast<std::uintptr_t>(big.data());
    const std::string flags = vmFlagsAt(big.data());
    if (!dexelmill::detail::hugePagesOnAdvice() || flags.empty()) {
        WARN("no transparent huge pages on advice here: the list's mapping is not checked");
        return;
    }
    CHECK(at % (std::size_t(2) << 20) == 0);
    CHECK(hasFlag(flags, "hg"));
    // Growing moves it to another such mapping and returns the first.
    big.resize(big.size() * 2);
    CHECK(reinterpret_cast<std::uintptr_t>(big.data()) % (std::size_t(2) << 20) == 0);
    CHECK(big[5 * 1024] == 5 * 1024);
    CHECK(vmFlagsAt(reinterpret_cast<const void*>(at)).empty());

    // A small list comes from operator new as before.
    List small(100, 7u);
    CHECK(small[99] == 7u);
}
