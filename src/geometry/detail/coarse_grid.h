/// @file coarse_grid.h
/// @brief A uniform grid of cubic cells over a box, for finding what lies near what: the
/// refinement's windows and swept cells, and the mesh's crossing triangles.
#pragma once

#include <array>
#include <cstddef>

#include "dexelmill/geometry/types.h"

namespace dexelmill::detail {

/// @brief A uniform grid of cubic cells covering a box: cells of a given size, doubled until there
/// are at most kMaxCells of them.
struct CoarseGrid {
    /// The most cells a grid may have (a dense index over them takes 4 bytes each).
    static constexpr double kMaxCells = double(std::size_t(1) << 22);

    Vec3 origin{0.0};
    double size = 1.0;
    std::array<int, 3> n{1, 1, 1};

    CoarseGrid() = default;
    CoarseGrid(const Box& box, double cell);
    std::size_t cellCount() const { return std::size_t(n[0]) * std::size_t(n[1]) * std::size_t(n[2]); }
    /// The cell index along axis a of coordinate x, clamped to the grid.
    int coord(int a, double x) const;
    std::size_t index(const std::array<int, 3>& c) const {
        return std::size_t(c[0]) + std::size_t(n[0]) * (std::size_t(c[1]) + std::size_t(n[1]) * std::size_t(c[2]));
    }
    /// The cells `box` grown by `grow` overlaps, in [c0, c1] per axis; false if it misses the grid.
    bool overlap(const Box& box, double grow, std::array<int, 3>& c0, std::array<int, 3>& c1) const;
};

}  // namespace dexelmill::detail
