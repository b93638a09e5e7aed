/// @file patches_apart.h
/// @brief The vertices of the table path's patches that share a cell, moved apart where their fans
/// pass through each other: each towards its loop's mass point until it stands on its own side of
/// a plane between the two loops. Pass 3 of contour.cpp. No OpenVDB here.
#pragma once

#include <cstdint>

#include "dexelmill/geometry/types.h"
#include "surface/detail/cell_table.h"

namespace dexelmill::detail {

/// @brief One patch of a cell: its vertex and the crossings of its loop, as indices into the mesh's
/// vertices, in the loop's order (its fan is vertex, loop[i], loop[i + 1]).
struct SharedPatch {
    std::uint32_t vertex = 0;
    std::uint32_t loop[kCellEdges] = {};
    int len = 0;
};

/// @brief What keepPatchesApart did in one cell.
struct PatchesApart {
    int moved = 0;  ///< vertices moved
    int leftCrossing =
        0;  ///< pairs whose fans cross but whose loops' hulls meet: left as they were
};

/// @brief For the `count` patches of one cell (their loops apart: a cell table's patches share no
/// crossing), the pairs whose fans pass through each other by more than `tol` (mm, trianglesCross)
/// have their vertices in `points` moved apart: see the definition. A pair whose loops' hulls meet
/// has no plane between them and is left crossing, and counted.
PatchesApart keepPatchesApart(const SharedPatch* patches, int count, Vec3* points, double tol);

}  // namespace dexelmill::detail
