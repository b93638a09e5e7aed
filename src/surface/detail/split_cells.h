/// @file split_cells.h
/// @brief The lattice cells round an edge whose dexel has several ends between the edge's two
/// lattice points (a wall, fin or slot thinner than the spacing, which no lattice point falls
/// in), and their loops (cell_loops.h): contour.cpp's general path. No OpenVDB here.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "dexelmill/geometry/packed_normal.h"
#include "dexelmill/geometry/types.h"
#include "dexelmill/stock/tridexel.h"
#include "dexelmill/surface/mesh.h"
#include "surface/detail/patch_vertex.h"

namespace dexelmill::detail {

/// @brief A lattice point in the level set's grid indices.
using GridPoint = std::array<int, 3>;

/// @brief What the general path reads of the level set and of the contourer.
struct SplitInputs {
    GridPoint offset{};  ///< the grid index of lattice point (0, 0, 0)
    /// The level set's value at a grid point (negative in material).
    std::function<float(const GridPoint&)> value;
    /// The contourer's crossing on the edge from `lower` along `axis`, whose ends differ
    /// (`lowerInside`: whether `lower` is in material): its offset in (0, 1) spacings from
    /// `lower`, and its normal (zero when unknown or sharp).
    std::function<std::pair<double, Vec3>(const GridPoint& lower, int axis, bool lowerInside)> crossing;
    /// Ends closer than this (in spacings) to a lattice point are moved this far from it.
    double cornerGap = 1e-3;
    /// Two ends of one edge closer than this (in spacings) are dropped together: a stretch of
    /// material or a gap this thin is left as the level set has it (out, or filled). Its volume is
    /// at most this times h^3 per edge. Such slivers come from surfaces that graze a lattice
    /// point, where their triangles would stand on edge.
    double minStretch = 0.02;
    /// ContourOptions::featureAngle: ends whose normals differ by more bound a sharp edge.
    double featureAngle = 0.6;
    /// Edges (lower grid point, axis) left to the table path, sorted; may be null.
    const std::vector<std::pair<GridPoint, int>>* excluded = nullptr;
};

/// @brief The general path's cells, vertices and loops.
struct SplitCells {
    /// Loop entries with this bit set are the contourer's crossings: ordinary[id & ~kOrdinary].
    static constexpr std::uint32_t kOrdinary = 1u << 31;
    /// Vertices of the general path: the ends on the edges with several (exact dexel ends, with
    /// their normals), then the face vertices (no normal).
    std::vector<Vec3> points;
    std::vector<PackedNormal> normals;
    std::size_t edgeEnds = 0;  ///< how many of `points` are ends (the rest are face vertices)
    /// Per end (points[k], k < edgeEnds): the end across the stretch of material it bounds on its
    /// edge, or kNoPartner where that stretch runs on to a lattice point.
    std::vector<std::uint32_t> partner;
    static constexpr std::uint32_t kNoPartner = ~0u;
    /// Per face vertex (points[edgeEnds + k]): the two ends (indices into `points`) it lies between.
    std::vector<std::array<std::uint32_t, 2>> faceVertexEnds;
    /// The contourer's crossings the loops use: edges by lower grid point and axis.
    std::vector<std::pair<GridPoint, int>> ordinary;
    /// Edges with several crossings, by lower grid point and axis, sorted: the contourer makes no
    /// crossing of its own on them.
    std::vector<std::pair<GridPoint, int>> edges;
    /// Cells (by lower grid point), sorted: the contourer's table path skips them.
    std::vector<GridPoint> cells;
    /// Patches: loop k is loopIds[loopStart[k] .. loopStart[k + 1]), in cell patchCell[k]; the
    /// patches of cells[c] are cellPatchStart[c] .. cellPatchStart[c + 1].
    std::vector<std::uint32_t> loopStart{0};
    std::vector<std::uint32_t> cellPatchStart{0};
    std::vector<std::uint32_t> loopIds;
    std::vector<GridPoint> patchCell;

    std::size_t patches() const { return patchCell.size(); }
};

/// @brief Split patch k's vertex `v` (PatchVertexRule::place), kept on its own side of the middle
/// of each stretch of material that an end of its loop bounds and another patch's end closes (a
/// fin thinner than the spacing, its sides within `featureAngle` of parallel), a quarter of that
/// end's distance from it, and within the box `lo` to `hi` (its cell, as place bounds it): see
/// the definition.
Vec3 keepOffFinMiddle(const SplitCells& cells, std::uint32_t k, double featureAngle, const Vec3& lo, const Vec3& hi,
                      Vec3 v);

/// @brief A split patch's vertex `v`, in the cell whose lowest corner is `cellLo` (spacing h), kept
/// PatchVertexRule::kFaceInset h inside each face that a path of its `loop` crosses (two
/// consecutive entries on that face, a lens's or one between two edges): see the definition.
Vec3 keepOffPathFaces(const PatchVertexRule::Loop& loop, const Vec3& cellLo, double h, Vec3 v);

/// @brief The triangles of split patches that pass through a triangle of another patch of their
/// cell by more than `tol` (mm, trianglesCross), each pair's two in turn: patch k's fan is its
/// loop's length in triangles of `mesh` from `firstTriangle[k]`. See the definition.
std::vector<std::uint32_t> crossingPatchTriangles(const SplitCells& cells, const Mesh& mesh,
                                                  const std::vector<std::uint32_t>& firstTriangle, double tol);

/// @brief Finds the edges of `stock`'s lattice whose dexel has two or more ends strictly between
/// its lattice points and agrees with the level set at both, the cells round them, and those
/// cells' loops. An edge whose dexel disagrees with the level set's sign at either point is left
/// to the contourer's table path.
SplitCells findSplitCells(const TriDexelStock& stock, const SplitInputs& in);

}  // namespace dexelmill::detail
