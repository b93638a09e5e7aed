/// @file crossings.h
/// @brief Triangles of a mesh that pass through one another: the refinement's guard against the
/// splits it makes, and the contourer's against patches of one cell whose fans cross.
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "dexelmill/surface/mesh.h"

namespace dexelmill::detail {

/// @brief Whether triangles a and b (their corners' indices and positions) pass through or overlap
/// each other, other than in the corners and edge they share.
///  - **Not in one plane.** Some edge of one crosses the other: its ends lie either side of the
///    plane by more than `tol` (mm), and the point where it passes lies inside each of the
///    triangle's edges by more than `tol`. Sharing no corner, each of the six edges is tested;
///    sharing one, only the edge of each opposite it (two triangles that meet at a corner and
///    cross meet along a segment from it, which ends on one of those edges). Two that share an
///    edge meet only along it.
///  - **In one plane** (every corner of each within `tol` of the other's plane): an edge of one
///    crosses an edge of the other, a corner of one lies inside the other, they have the same
///    corners, or, sharing an edge, their other corners lie on the same side of it (one folded
///    onto the other), each by more than `tol`. A vertex moved within a flat face can fold a
///    triangle over its neighbour this way without checkMesh seeing a fold.
/// Contacts within `tol` are not counted, nor triangles of no area.
bool trianglesCross(const std::array<std::uint32_t, 3>& ia, const std::array<Vec3, 3>& a,
                    const std::array<std::uint32_t, 3>& ib, const std::array<Vec3, 3>& b,
                    double tol);

/// @brief The pairs (i, j) of a triangle a[i] (i < na) of one fan and b[j] (j < nb) of another,
/// their corners indices into `points`, that pass through each other (trianglesCross, `tol`), by
/// i, then j: the test of two patches of one cell whose fans cross, the table path's
/// (keepPatchesApart) and the split cells' (crossingPatchTriangles).
std::vector<std::pair<int, int>> fanCrossings(const Mesh::Triangle* a, int na,
                                              const Mesh::Triangle* b, int nb, const Vec3* points,
                                              double tol);

/// @brief The triangles of `mesh` that take part in a crossing (trianglesCross) of a triangle
/// listed in `pieces` (increasing) with one listed in `partners` (which should hold the pieces),
/// each listed once, in increasing order. Pieces are found through a coarse grid of their boxes.
/// Runs in the caller's task arena; the answer does not depend on the thread count.
std::vector<std::uint32_t> crossingTriangles(const Mesh& mesh,
                                             const std::vector<std::uint32_t>& pieces,
                                             const std::vector<std::uint32_t>& partners,
                                             double tol);

}  // namespace dexelmill::detail
