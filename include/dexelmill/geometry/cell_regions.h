/// @file cell_regions.h
/// @brief Cells of a regular grid grouped into regions of cells that touch: how the excess after a
/// cut and the features finer than the lattice gather their stretches into places.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace dexelmill {

/// @brief Groups cells of a grid of dims[0] x dims[1] x dims[2] cells (cell x, y, z has index
/// x + dims[0] (y + dims[1] z)) into regions of cells that touch by a face, an edge or a corner.
/// Returns the region of each cell in `cells`, in order; regions are numbered from 0 as their
/// first cell comes in `cells` (a cell given twice gets its region twice).
std::vector<std::uint32_t> touchingRegions(const std::array<std::int64_t, 3>& dims, const std::vector<std::size_t>& cells);

}  // namespace dexelmill
