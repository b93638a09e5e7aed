/// @file builders.h
/// @brief Builders for the common cutters and the APT 7-parameter cutter. Lengths in mm, angles
/// in radians. Every builder throws dexelmill::Error naming the parameter and its value when the
/// parameters describe no real tool, or one larger than kMaxToolSizeMm (tool.h).
#pragma once

#include "dexelmill/tool/tool.h"

namespace dexelmill {

/// @brief Cutting length and total length (stick-out) of a tool, in mm. Zero means "default":
/// the cutting length defaults to 3 cutting diameters (at least 10 mm, and no more than a total
/// length given), the total length to 2 diameters more than the cutting length or the shaped end
/// (a ball, a drill's point), whichever is longer; neither beyond kMaxToolSizeMm.
struct ToolLengths {
    double cutting = 0.0;
    double total = 0.0;
};

/// @brief Flat end mill of diameter d.
Tool flatEndMill(double d, ToolLengths lengths = {});
/// @brief Ball end mill of diameter d.
Tool ballEndMill(double d, ToolLengths lengths = {});
/// @brief Bull-nose (toroidal, fillet-end) mill of diameter d with corner radius r, 0 < r <= d/2.
Tool bullNoseEndMill(double d, double r, ToolLengths lengths = {});
/// @brief Tapered end mill: flat tip of diameter tipD, flank at halfAngle from the axis,
/// widening over the whole cutting length; the shank above keeps the top radius.
Tool taperEndMill(double tipD, double halfAngle, ToolLengths lengths = {});
/// @brief Chamfer mill or V-bit: flat tip of diameter tipD (0 for a V-bit), flank at halfAngle
/// from the axis up to diameter d, then cylindrical.
Tool chamferMill(double tipD, double halfAngle, double d, ToolLengths lengths = {});
/// @brief Tapered ball mill: ball of diameter ballD at the tip, tangent to a flank at halfAngle
/// from the axis.
Tool taperBallMill(double ballD, double halfAngle, ToolLengths lengths = {});
/// @brief Twist drill of diameter d with included point angle (e.g. 118 degrees, in radians).
Tool drill(double d, double pointAngle, ToolLengths lengths = {});

/// @brief `tool` in a cylindrical holder of diameter d, from its stick-out (totalLength()) up for
/// `length`: part of the tool above the cutting length, so material it meets is a collision, as the
/// shank's is. The holder is one cylinder: d should be that of its widest part within `length` of
/// the stick-out (a collet nut's, or a shrink-fit chuck's body), so that the cylinder holds it.
/// @throw Error if d is narrower than the tool at its top or a value is not a positive length, or
/// if the tool with its holder is longer than kMaxToolSizeMm.
Tool withHolder(const Tool& tool, double d, double length);

/// @brief How far a CUTTER value may lie from the one meant, as CL files print it: to six
/// significant digits or four decimal places of its unit, whichever is coarser (1.984375 mm is
/// printed 1.98438; Autodesk's short APT format prints four decimals).
/// @param unit the unit the value was printed in, in the value's units: 1 for a length in mm or an
/// angle in degrees, 25.4 for a length in mm printed in inches.
double cutterRounding(double value, double unit);

/// @brief The APT `CUTTER/d, r, e, f, alpha, beta, h` cutter: corner circle of radius r centred
/// (e, f) in the (radial, axial) plane, bottom flank at alpha above the horizontal, side flank at
/// beta from the vertical, height h. With r = 0 the corner is the sharp point (e, f) and the
/// bottom flank runs through it, leaving a flat tip where it meets z = 0 (chamfer mills). The
/// relations the values must meet (d/2 = e + r cos(beta), f = r where alpha = 0, r <= d/2, the
/// corner above the tip) need hold only within the rounding of printed values (cutterRounding);
/// the profile is built from r, e, f, alpha and beta, so d is the one value it does not use.
/// @param cuttingLength flute length; 0 means all of h.
/// @param lengthUnit the length unit the values were printed in, in mm (25.4 for inches).
Tool aptCutter(double d, double r, double e, double f, double alpha, double beta, double h,
               double cuttingLength = 0.0, double lengthUnit = 1.0);

}  // namespace dexelmill
