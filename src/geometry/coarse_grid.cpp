#include "geometry/detail/coarse_grid.h"

#include <algorithm>
#include <cmath>

namespace dexelmill::detail {

CoarseGrid::CoarseGrid(const Box& box, double cell) : origin(box.lo), size(std::max(cell, 1e-6)) {
    const Vec3 span = box.size() + Vec3(1e-9);
    while (std::ceil(span.x / size) * std::ceil(span.y / size) * std::ceil(span.z / size) > kMaxCells) size *= 2.0;
    for (int a = 0; a < 3; ++a) n[a] = std::max(1, int(std::ceil(span[a] / size)));
}

int CoarseGrid::coord(int a, double x) const {
    return std::clamp(int(std::floor((x - origin[a]) / size)), 0, n[a] - 1);
}

bool CoarseGrid::overlap(const Box& box, double grow, std::array<int, 3>& c0, std::array<int, 3>& c1) const {
    for (int a = 0; a < 3; ++a) {
        const double lo = box.lo[a] - grow, hi = box.hi[a] + grow;
        if (hi < origin[a] || lo > origin[a] + n[a] * size) return false;
        c0[a] = coord(a, lo), c1[a] = coord(a, hi);
    }
    return true;
}

}  // namespace dexelmill::detail
