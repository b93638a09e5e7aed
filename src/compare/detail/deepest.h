// The deepest point of a set of dexel stretches inside (or outside) a mesh: a branch and bound
// over pieces of the stretches with exact distances, shared by the gouge and excess searches.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

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

}  // namespace dexelmill
