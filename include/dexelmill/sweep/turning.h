/// @file turning.h
/// @brief Moves whose tool axis turns (simultaneous 5-axis): the angle they turn through, and a
/// box every pose of the tool stays in. The cutting loop does not sweep them yet; the job uses
/// these to refuse a turning move that can reach the stock and to let one in the air pass.
///
/// Motion law (APT MULTAX): the tip runs on the straight line from `start` to `end` and the unit
/// axis turns on the great circle from `startAxis` to `axis` (the shorter arc, at a uniform rate).
#pragma once

#include "dexelmill/path/toolpath.h"

namespace dexelmill {

/// @brief The angle (radians, in [0, pi]) the axis of a move turns through; 0 for a fixed axis.
double turnAngle(const Move& move);

/// @brief A box that holds the tool (within `radius` of its axis, heights [0, length] above the
/// tip) at every pose of a turning move; for a fixed-axis move, at its one axis.
///
/// The box is the tip's segment box plus the box of the turning cylinder (that radius and length)
/// with its tip held at the origin. The second is exact: each of its faces touches some pose. The
/// sum is exact for a turn in place and larger than needed when the tip's extreme and the axis's
/// lie at different points of the move (at most by the tip's travel along each coordinate).
/// Along the arc a(t) = a0 cos t + b sin t (b the unit tangent at a0, t in [0, theta]) each
/// coordinate a_i is rho cos(t - phi), whose extremes are at the ends and where t - phi is 0 or
/// pi. A tool point is tip + s a + r n with s in [0, length], |r| <= radius and n a unit vector
/// normal to a; along a unit direction e with c = a.e it reaches
/// g(c) = length max(c, 0) + radius sqrt(1 - c^2), concave on [-1, 0] and on [0, 1] with peaks
/// at 0 and length / hypot(length, radius), so the ends of c's range and those peaks bound it.
/// @throw Error if the axes are opposite (no one great circle joins them).
Box turningMoveBox(const Move& move, double length, double radius);

}  // namespace dexelmill
