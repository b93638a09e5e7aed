/// @file simplify.h
/// @brief Edge collapses that keep a closed mesh a closed, oriented 2-manifold without folds:
/// merging its flat regions, and removing its shortest edges. No OpenVDB here.
#pragma once

#include <cstddef>

#include "dexelmill/surface/mesh.h"

namespace dexelmill {

/// @brief Limits of mergeFlatRegions.
struct FlatMergeOptions {
    /// A vertex is merged away only when the normals of its triangles, before and after, stay
    /// within this angle (radians) of their mean.
    double maxAngle = 0.0;
    /// ... and when it lies within this distance (mm) of every triangle that replaces its own.
    double maxDistance = 0.0;
};

/// @brief Collapses edges inside flat regions: a vertex u goes into a neighbour v (which keeps its
/// place) when every triangle around u, and every triangle that u's collapse leaves, faces within
/// maxAngle of the mean normal of u's triangles, and u lies within maxDistance of each new
/// triangle's plane. So the surface moves by at most maxDistance, and creases (whose two sides
/// differ by more than maxAngle) keep their vertices.
///
/// A collapse is made only when the vertices next to both u and v are exactly the two across
/// their shared edge (the link condition of Dey et al. 1999), which keeps a closed 2-manifold
/// closed and manifold, and when no new triangle is degenerate. Vertices are visited in index
/// order, pass after pass until a pass merges nothing: the result does not depend on threads.
/// Unused vertices are removed at the end.
/// @return the number of vertices merged away.
std::size_t mergeFlatRegions(Mesh& mesh, const FlatMergeOptions& options);

/// @brief Collapses the edges shorter than `length` (mm), shortest first: the newer end (the higher
/// index) goes into the older, which keeps its place and is not collapsed itself afterwards, so
/// every vertex removed lies within `length` of one kept, and the surface moves by less than that.
/// A collapse is made only under the link condition (above), and when every triangle the newer
/// end leaves is not degenerate and faces the way of the two ends' triangles together (the sum of
/// their area vectors): a crumple, where triangles a few micrometres across face every way round
/// vertices that nearly coincide, is smoothed out, and nothing is turned over. Unused vertices are
/// removed at the end.
/// @return the number of edges collapsed.
std::size_t collapseShortEdges(Mesh& mesh, double length);

}  // namespace dexelmill
