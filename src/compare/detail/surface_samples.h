// Points spread over a mesh's triangles, so that every point of its surface lies near one of them:
// the sampling the deviation is measured at (measureDeviation), with the area each point stands for.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/surface/mesh.h"

namespace dexelmill {

/// How one triangle is sampled at a spacing s (see sampleSurface).
struct TrianglePattern {
    /// The lattice: the triangle cut into k^2 copies of itself scaled by 1 / k, measured at their
    /// corners. 1 when it is measured at its own corners alone; 0 when it is sampled by rows.
    std::uint64_t pieces = 1;
    /// Rows: the number of rows parallel to the longest edge (0 for the lattice).
    std::uint64_t rows = 0;
    /// Rows: the most a row's points lie apart (mm).
    double along = 0.0;
    /// The points the pattern adds to the triangle's corners.
    std::uint64_t added = 0;
};

/// A triangle's size as the patterns need it: its longest edge (mm) and its height over that edge.
struct TriangleShape {
    double longest = 0.0, height = 0.0;
};

/// The pattern with fewer points for a triangle of this shape at spacing `spacing` (the lattice
/// where both add as many). Every point of the triangle then lies within spacing / sqrt(3) of a
/// point of the pattern (its corners included).
TrianglePattern trianglePattern(const TriangleShape& shape, double spacing);

/// The points a mesh is measured at: its vertices, and points inside its triangles.
struct SurfaceSamples {
    /// Every point of the mesh lies within spacing / sqrt(3) of a vertex or of a point (mm).
    double spacing = 0.0;
    /// The area (mm^2) each vertex stands for, and the points inside the triangles with theirs:
    /// together the mesh's area, each share of it lying within spacing of its point.
    std::vector<double> vertexArea;
    std::vector<Vec3> points;
    std::vector<double> pointArea;
};

/// The sampling of `mesh` at the finest spacing, from `finest` (mm, above 0; and never below 1e-6
/// of the longest edge) up, whose points inside the triangles number at most `budget`, found by
/// bisection to within 2 % (see surface_samples.cpp).
/// Runs in parallel on the calling arena.
SurfaceSamples sampleSurface(const Mesh& mesh, double finest, std::uint64_t budget);

}  // namespace dexelmill
