/// @file offset.h
/// @brief A convex part of a tool grown by a distance r: the set of points within r of it, as a
/// chain of profile pieces in the same tool frame. The sweep of a turning tool (turning.h) bounds
/// the poses between two it has solved by such offsets.
///
/// The offset of a solid of revolution is a solid of revolution, and its meridian section is the
/// section grown by a disk of radius r. For a convex section the boundary of the grown section is
/// the boundary moved out by r along its outward normals, with a circular arc of radius r round
/// every corner where the normal jumps:
///  - a cone piece (normal constant along it) moves by r times its normal: a cone of the same
///    height;
///  - an arc piece of radius rho keeps its centre and gets radius rho + r;
///  - the bottom face (normal -z) moves down by r and the top face (normal +z) up by r; they need
///    no piece (the chain's slab solids hold them);
///  - a corner between normals at angles psi_a < psi_b (psi = atan2(nz, nr), in [-pi/2, pi/2] and
///    increasing up a convex chain) becomes the arc piece of radius r centred on the corner,
///    heights zc + r sin(psi_a) to zc + r sin(psi_b). The bottom face meets the lowest piece at
///    (R(z0), z0), a corner even when R(z0) = 0 (a drill's or V-bit's apex); a ball's tip, whose
///    normal is already -z, has none.
/// The chain's heights start r below the part and end r above it, so they can be negative.
#pragma once

#include <vector>

#include "dexelmill/tool/line_query.h"
#include "dexelmill/tool/tool.h"

namespace dexelmill {

/// @brief The pieces of `part` of `tool` grown by r >= 0, bottom to top (see the file comment).
std::vector<ProfilePiece> offsetPart(const Tool& tool, const ConvexPart& part, double r);

/// @brief The interval of `line` inside the convex solid that `pieces` describe (the hull of the
/// pieces' slab solids), in the line's own parameters (LocalLine::vShift added back).
Interval intersectPieces(const std::vector<ProfilePiece>& pieces, const LocalLine& line);

}  // namespace dexelmill
