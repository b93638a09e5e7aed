/// @file feature_snap.h
/// @brief Feature-preserving vertex placement from the exact dexel crossings (dual contouring
/// with Hermite data, Ju et al. 2002; method.md section 7). No OpenVDB here.
#pragma once

#include <cstddef>

#include "dexelmill/stock/tridexel.h"
#include "dexelmill/surface/mesh.h"

namespace dexelmill {

/// @brief Options of snapFeatures.
struct SnapOptions {
    /// Normals closer than this angle (radians) count as one plane: a cell whose crossings'
    /// normals spread less keeps a vertex on their mean plane; a wider spread resolves an edge
    /// (two planes) or a corner (three). The QEF drops eigenvalues below tan^2(angle / 2) of the
    /// largest.
    double featureAngle = 0.6;
    /// A solution farther than this (in h) outside the vertex's cell is rejected: the vertex
    /// stays where it was.
    double maxOutside = 0.5;
};

/// @brief What snapFeatures did.
struct SnapStats {
    std::size_t planeVertices = 0;   ///< placed on one plane (smooth cells)
    std::size_t edgeVertices = 0;    ///< placed on the line of two planes
    std::size_t cornerVertices = 0;  ///< placed at the point of three planes
    std::size_t kept = 0;  ///< left alone: no crossings, a shared cell, or a rejected solution
};

/// @brief Moves each vertex of a mesh of the stock's level set (meshLevelSet with adaptivity 0,
/// one vertex per lattice cell) to the point that best fits the exact crossings on its cell's
/// twelve edges: minimise sum_i (n_i . (x - p_i))^2 around their mean with a truncated
/// pseudo-inverse. p_i are dexel endpoints; n_i are estimated from the same family's
/// neighbouring dexels (the one-sided difference of crossing positions with the smaller slope on
/// each side, so a face's normal stays exact up to a sharp edge). Cells holding more than one
/// vertex are left alone.
SnapStats snapFeatures(Mesh& mesh, const TriDexelStock& stock, const SnapOptions& options = {});

}  // namespace dexelmill
