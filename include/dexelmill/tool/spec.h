/// @file spec.h
/// @brief Tools written as short text, as on the command line:
///
///     ball:d=6            flat:d=10           bull:d=10,r=2
///     taper:d=2,angle=15  chamfer:d=12,angle=45[,tip=0]   vbit:d=6,angle=30
///     taperball:d=3,angle=5                   drill:d=6[,angle=118]
///     apt:D,R,E,F,ALPHA,BETA,H
///
/// followed by optional `,length=L` (cutting length), `,total=T` (stick-out) and
/// `,holder=D,holderlength=L` (a cylindrical holder above the stick-out, withHolder). Lengths in mm,
/// angles in degrees: for taper, chamfer, vbit and taperball the half angle from the axis, for
/// drill the included point angle. d is the tip's diameter for taper (which widens over the
/// cutting length), the largest for chamfer and vbit (whose tip is `tip=`, 0 unless given), the
/// ball's for taperball.
#pragma once

#include <string>

#include "dexelmill/tool/tool.h"

namespace dexelmill {

/// @brief Builds the tool a spec describes.
/// @throw Error naming the spec and the part of it that is wrong.
Tool parseToolSpec(const std::string& spec);

}  // namespace dexelmill
