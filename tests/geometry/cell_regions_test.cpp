// Cells grouped into touching regions, against a flood fill over the whole grid.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <deque>
#include <random>
#include <vector>

#include "dexelmill/geometry/cell_regions.h"

using namespace dexelmill;

namespace {

/// The region of every given cell by a breadth-first fill of the dense grid over its 26
/// neighbours, numbered as the regions' first cells come.
std::vector<std::uint32_t> floodFill(const std::array<std::int64_t, 3>& dims, const std::vector<std::size_t>& cells) {
    const std::size_t n = std::size_t(dims[0] * dims[1] * dims[2]);
    std::vector<char> occupied(n, 0);
    for (std::size_t c : cells) occupied[c] = 1;
    std::vector<std::int64_t> region(n, -1);
    std::vector<std::uint32_t> out;
    std::uint32_t next = 0;
    for (std::size_t c : cells) {
        if (region[c] < 0) {
            std::deque<std::size_t> queue{c};
            region[c] = next;
            while (!queue.empty()) {
                const auto k = std::int64_t(queue.front());
                queue.pop_front();
                const std::int64_t x = k % dims[0], y = k / dims[0] % dims[1], z = k / (dims[0] * dims[1]);
                for (std::int64_t nz = z - 1; nz <= z + 1; ++nz)
                    for (std::int64_t ny = y - 1; ny <= y + 1; ++ny)
                        for (std::int64_t nx = x - 1; nx <= x + 1; ++nx) {
                            if (nx < 0 || ny < 0 || nz < 0 || nx >= dims[0] || ny >= dims[1] || nz >= dims[2]) continue;
                            const auto m = std::size_t(nx + dims[0] * (ny + dims[1] * nz));
                            if (occupied[m] && region[m] < 0) region[m] = next, queue.push_back(m);
                        }
            }
            ++next;
        }
        out.push_back(std::uint32_t(region[c]));
    }
    return out;
}

}  // namespace

TEST_CASE("touching regions agree with a flood fill", "[geometry][regions]") {
    std::uint32_t mostRegions = 0;
    for (const unsigned seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
        std::mt19937 rng(seed);
        const std::array<std::int64_t, 3> dims{std::int64_t(rng() % 9 + 1), std::int64_t(rng() % 9 + 1),
                                               std::int64_t(rng() % 9 + 1)};
        const std::size_t n = std::size_t(dims[0] * dims[1] * dims[2]);
        // Sparse enough for many regions, with cells given more than once.
        std::vector<std::size_t> cells(n / 5 + 3);
        for (std::size_t& c : cells) c = rng() % n;
        INFO("seed " << seed << ", grid " << dims[0] << " x " << dims[1] << " x " << dims[2]);
        const std::vector<std::uint32_t> regions = touchingRegions(dims, cells);
        CHECK(regions == floodFill(dims, cells));
        for (std::uint32_t r : regions) mostRegions = std::max(mostRegions, r + 1);
    }
    // The cases hold several regions, not one each.
    CHECK(mostRegions >= 3);
}

TEST_CASE("touching regions: corners touch, a gap of one cell parts", "[geometry][regions][degenerate]") {
    const std::array<std::int64_t, 3> dims{4, 4, 4};
    const auto at = [&](std::int64_t x, std::int64_t y, std::int64_t z) { return std::size_t(x + 4 * (y + 4 * z)); };
    CHECK(touchingRegions(dims, {}).empty());
    CHECK(touchingRegions(dims, {at(0, 0, 0), at(1, 1, 1)}) == std::vector<std::uint32_t>{0, 0});
    CHECK(touchingRegions(dims, {at(0, 0, 0), at(2, 0, 0), at(0, 0, 0)}) == std::vector<std::uint32_t>{0, 1, 0});
    // Cells at the grid's opposite faces do not wrap around.
    CHECK(touchingRegions(dims, {at(3, 0, 0), at(0, 1, 0)}) == std::vector<std::uint32_t>{0, 1});
}
