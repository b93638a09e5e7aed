// The deepest point of a set of dexel stretches inside (or outside) a mesh: a branch and bound
// over pieces of the stretches with exact distances, shared by the gouge and excess searches.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "dexelmill/compare/design.h"
#include "dexelmill/compare/mesh_distance.h"
#include "dexelmill/span.h"
#include "dexelmill/stock/lattice.h"

namespace dexelmill {

/// A stretch [lo, hi] of one dexel (coordinates along it relative to the lattice origin, mm).
struct DexelStretch {
    Axis family = Axis::Z;
    int ib = 0, ic = 0;
    double lo = 0.0, hi = 0.0;
    /// No point of the stretch is farther from the mesh than this (mm), when the caller knows it.
    double bound = std::numeric_limits<double>::infinity();
};

/// Stretches lying one after another in memory.
using StretchSpan = Span<DexelStretch>;

struct Deepest {
    double depth = -std::numeric_limits<double>::infinity();  ///< mm; -infinity without stretches
    Vec3 point{0.0};
};

/// The point of `stretches` farthest from the mesh, within `eps` (mm) of the farthest: its
/// distance is that of a real point, and no point lies farther than depth + eps.
Deepest deepestPoint(const MeshDistance& distance, const Lattice& lattice, StretchSpan stretches,
                     double eps);

/// How far from its stretches (in lattice spacings) a first, local index looks for triangles
/// (deepestPoints).
constexpr double kNearSpacings = 4.0;

/// deepestPoint for each group of `stretches` (group g is [groups[g], groups[g + 1])), searched
/// first with an index of only the design's triangles near them (DesignPart::distanceNear).
///
/// Each stretch takes the triangles whose boxes meet its points' box grown by r, the smaller of
/// its bound and kNearSpacings h. A triangle left out lies farther than r from every point of the
/// stretch, so a local distance d at one of its points is exact when d <= r, and the true
/// distance is above r otherwise. When r is the stretch's bound, every local distance there is
/// exact. A group is searched again with the whole index when its deepest point lies deeper than
/// the smallest r of its stretches that is not their bound: otherwise every sample the search took
/// (none deeper than its deepest) was exact, and every bound it drew from a triangle is a true
/// bound, so the result is the one the whole index gives, within eps. Gouges and excess along
/// grazing dexels reach far along them and lie close to the surface: their search needs only the
/// triangles nearby.
std::vector<Deepest> deepestPoints(const DesignPart& design, const Lattice& lattice,
                                   const std::vector<DexelStretch>& stretches, const std::vector<std::size_t>& groups,
                                   double eps);

}  // namespace dexelmill
