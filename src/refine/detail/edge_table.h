/// @file edge_table.h
/// @brief The undirected edges of some of a mesh's triangles.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "dexelmill/surface/mesh.h"

namespace dexelmill::detail {

constexpr std::uint32_t kNoTriangle = std::numeric_limits<std::uint32_t>::max();

/// @brief The edges of the triangles `triangles[i]` of a mesh (i: the local triangle). Slot 3 i + k
/// is local triangle i's edge from corner k to corner k + 1.
struct EdgeTable {
    std::vector<std::uint32_t> edgeOf;                    ///< per slot, its edge
    std::vector<std::array<std::uint32_t, 2>> ends;       ///< per edge, its vertices (lower first)
    /// Per edge, the two local triangles that share it, running it in opposite directions;
    /// kNoTriangle for an edge with one slot, or with more than one slot either way.
    std::vector<std::array<std::uint32_t, 2>> triangles;
};

/// @brief The edge table of `mesh`'s triangles listed in `triangles` (global indices).
EdgeTable buildEdges(const Mesh& mesh, const std::vector<std::uint32_t>& triangles);

}  // namespace dexelmill::detail
