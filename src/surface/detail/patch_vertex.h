/// @file patch_vertex.h
/// @brief The dexel mesher's vertex inside a cell: where the tangent planes of a patch's
/// crossings meet best (the quadric error function of dual contouring, solved by a truncated
/// SVD), kept within its cell and, on a smooth patch, where no fan triangle stands on edge. Pass 3
/// of contour.cpp. No OpenVDB here.
#pragma once

#include <cstdint>

#include "dexelmill/geometry/packed_normal.h"
#include "dexelmill/geometry/types.h"

namespace dexelmill::detail {

/// @brief Places patch vertices (see place) for one lattice spacing and feature angle.
class PatchVertexRule {
public:
    /// @param h the lattice spacing (mm)
    /// @param featureAngle ContourOptions::featureAngle: normals of one patch closer than this
    /// (radians) count as one smooth surface
    PatchVertexRule(double h, double featureAngle);

    /// @brief A patch's loop of crossings: `len` indices into the crossings' positions and packed
    /// normals (a normal that is absent or marked sharp adds no tangent plane). A cell table's
    /// loop has 3 to 12 crossings; a split cell's (split_cells.h) may have more, and one longer
    /// than kMaxPlanes takes its mass point.
    struct Loop {
        const Vec3* points;
        const PackedNormal* normals;
        const std::uint32_t* index;
        int len;
    };

    /// @brief The mean of the loop's crossings.
    static Vec3 massPoint(const Loop& loop);

    /// @brief Loops with more crossings than this are not fitted (see Loop).
    static constexpr int kMaxPlanes = 64;

    /// @brief A crease's or corner's vertex (rank 2 or 3) stays this far (in h) inside its cell's
    /// faces. On a face, its fan over a path of the loop across that face (a lens, cell_loops.h)
    /// would lie in the face, where it overlaps itself if the lens rises past the vertex. (Heart,
    /// the lattice plane x = 1.1647 at (19.50, -4.67): a convex crease's vertex, kept within its
    /// crossings' box, sat on the face 0.04 mm above a lens's face vertex, and three fan triangles
    /// overlapped.) Off the face, two fan triangles that share an edge meet only along it. It
    /// moves a vertex by at most 1e-3 h, as kCornerGap moves a crossing off a lattice point. A
    /// smooth patch's vertex keeps the whole cell: where its loop is a sliver kCornerGap from a
    /// lattice point, the inset would stand the fan over the sliver on edge, past fanOffset's
    /// bound (62 triangles of the contour tests' grazing spheres). A split cell's vertex is kept
    /// off the faces its loop crosses whatever the rank (keepOffPathFaces, split_cells.h).
    static constexpr double kFaceInset = 1e-3;

    /// @brief The patch's vertex in the cell whose lowest corner is `cellLo`; `rank` is the rank
    /// the truncated SVD kept: 0 (no plane: the mass point), 1 (a smooth patch), 2 (a crease,
    /// the vertex on it) or 3 (a corner). `sharesCell`: the cell holds other patches, and the
    /// vertex stays within the box of the loop's crossings (see the definition).
    Vec3 place(const Loop& loop, const Vec3& cellLo, bool sharesCell, int& rank) const;

private:
    double h_;
    double singular_;        ///< tan^2(featureAngle / 2): the eigenvalue ratio the SVD keeps
    double cosHalfFeature_;  ///< cos(featureAngle / 2): the smooth patch's test
};

}  // namespace dexelmill::detail
