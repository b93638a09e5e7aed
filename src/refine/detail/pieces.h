/// @file pieces.h
/// @brief How a triangle with some of its edges split is cut into pieces, and when it may not be.
#pragma once

#include <array>

#include "dexelmill/geometry/types.h"

namespace dexelmill::detail {

/// Local indices of a triangle being split: corners 0-2, and the new vertex of edge k (corner k to
/// corner k + 1) at 3 + k.
using Local = std::array<int, 3>;

/// @brief The pieces of a triangle whose edges in `mask` (bit k: edge k) are split, oriented as the
/// triangle, from the positions `p` (indexed as Local) and the triangle's unit normal `n`.
/// Returns the count (2, 3 or 4), or 0 if some piece would face away from the triangle (a cosine
/// below kMinCosine), be a sliver (kSliver) or a cap, with an angle above 170 degrees (kCapCosine);
/// for two split edges the quad's other diagonal is tried before giving up.
int splitPieces(const std::array<Vec3, 6>& p, unsigned mask, const Vec3& n, std::array<Local, 4>& out);

}  // namespace dexelmill::detail
