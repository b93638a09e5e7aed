/// @file frame.h
/// @brief The tool coordinate system of a linear move (method.md section 1, the paper's
/// Eqs. 1-2): axis n, e = n x f / |n x f|, d = e x n.
#pragma once

#include "dexelmill/geometry/types.h"

namespace dexelmill {

/// @brief Orthonormal tool frame (d, e, n) for a move with feed vector f along a tool axis.
///
/// `n` is the unit tool axis (the tool extends from its tip along +n). For a general move
/// `e = n x f / |n x f|` is perpendicular to the feed and `d = e x n` is the feed direction's
/// component perpendicular to the axis, so f = (d.f) d + (n.f) n. When f is parallel to n
/// (a plunge or a retract) or f = 0, `e` is undefined by the paper's formula; `plunge` is then
/// true and (d, e) is an arbitrary but deterministic orthonormal pair perpendicular to n.
struct ToolFrame {
    Vec3 n{0.0, 0.0, 1.0};
    Vec3 e{0.0, 1.0, 0.0};
    Vec3 d{1.0, 0.0, 0.0};
    bool plunge = true;

    /// @brief The frame of a move with tool axis `axis` (any length > 0) and feed vector `feed`.
    /// @throw Error if `axis` has zero length.
    static ToolFrame make(const Vec3& axis, const Vec3& feed);

    /// @brief An orthonormal pair perpendicular to a unit vector, chosen deterministically.
    static void perpendicularPair(const Vec3& n, Vec3& b1, Vec3& b2);
};

}  // namespace dexelmill
