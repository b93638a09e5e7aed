#include "dexelmill/geometry/cell_regions.h"

#include <algorithm>

#include <boost/pending/disjoint_sets.hpp>

namespace dexelmill {

std::vector<std::uint32_t> touchingRegions(const std::array<std::int64_t, 3>& dims, const std::vector<std::size_t>& cells) {
    // The distinct cells, sorted, joined to every neighbour that is one of them.
    std::vector<std::size_t> distinct = cells;
    std::sort(distinct.begin(), distinct.end());
    distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
    const auto indexOf = [&](std::size_t cell) {
        return std::size_t(std::lower_bound(distinct.begin(), distinct.end(), cell) - distinct.begin());
    };
    boost::disjoint_sets_with_storage<> sets(distinct.size());
    for (std::size_t i = 0; i < distinct.size(); ++i) {
        const auto k = std::int64_t(distinct[i]);
        const std::int64_t x = k % dims[0], y = (k / dims[0]) % dims[1], z = k / (dims[0] * dims[1]);
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const std::int64_t nx = x + dx, ny = y + dy, nz = z + dz;
                    if (nx < 0 || ny < 0 || nz < 0 || nx >= dims[0] || ny >= dims[1] || nz >= dims[2]) continue;
                    const auto neighbour = std::size_t(nx + dims[0] * (ny + dims[1] * nz));
                    const std::size_t j = indexOf(neighbour);
                    if (j < distinct.size() && distinct[j] == neighbour) sets.union_set(i, j);
                }
    }
    // Each root's number, as its region's first cell comes.
    constexpr std::uint32_t kNone = ~std::uint32_t(0);
    std::vector<std::uint32_t> numberOfRoot(distinct.size(), kNone), out(cells.size());
    std::uint32_t next = 0;
    for (std::size_t i = 0; i < cells.size(); ++i) {
        std::uint32_t& n = numberOfRoot[sets.find_set(indexOf(cells[i]))];
        if (n == kNone) n = next++;
        out[i] = n;
    }
    return out;
}

}  // namespace dexelmill
