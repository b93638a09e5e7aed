/// @file tool.h
/// @brief A milling cutter: a validated profile, its lengths, and exact point and line queries.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/tool/line_query.h"
#include "dexelmill/tool/profile.h"

namespace dexelmill {

/// @brief The largest size (mm) of a tool: its diameters and lengths, given or derived (a V-bit's
/// cone, a taper's top). No machine carries a cutter, or a stick-out, of 10 m. And the sweep needs
/// a bound, as its rounding grows with the square of the tool's size: a tilted bull nose's swept
/// surface comes out within 2e-11 mm of the exact one at 1 m across, 3e-9 mm at this size, 2e-7 mm
/// at 100 m and 3 mm at 1 km (tests/sweep/sweep_test.cpp checks 1e-7 mm at this size).
constexpr double kMaxToolSizeMm = 1e4;

/// @brief A maximal run of pieces whose solid is convex (R concave and continuous over it).
struct ConvexPart {
    std::size_t first = 0;  ///< index of the first piece
    std::size_t last = 0;   ///< index one past the last piece
    double z0 = 0.0, z1 = 0.0;
};

/// @brief A cutter as a solid of revolution: see profile.h.
///
/// The pieces cover [bottom, totalLength] without gaps or overlaps; bottom is 0 for a whole
/// tool. The part above `cuttingLength` is
/// the shank: it does not cut, and material it meets is a collision.
class Tool {
  public:
    /// @brief Validates and takes a profile chain.
    /// @throw Error if the chain is empty, starts below the tip, has gaps or overlaps, a negative
    /// radius, a zero-height piece, an arc outside its circle, no positive radius, a diameter or a
    /// length beyond kMaxToolSizeMm, or if cuttingLength is not in (0, total length].
    Tool(std::string description, std::vector<ProfilePiece> pieces, double cuttingLength);

    /// @brief What the tool is, e.g. "ball D6 L25/50".
    const std::string& description() const { return description_; }
    const std::vector<ProfilePiece>& pieces() const { return pieces_; }
    /// @brief The convex parts, bottom to top. One part for every common cutter.
    const std::vector<ConvexPart>& convexParts() const { return parts_; }
    bool isConvex() const { return parts_.size() == 1; }

    double totalLength() const { return totalLength_; }
    /// @brief Whether the solid holds a holder above the stick-out (withHolder), so that what its
    /// part above the cutting length meets may be the holder's rather than the shank's.
    bool hasHolder() const { return holderBottom_ < totalLength_; }
    /// @brief Where the holder starts (the stick-out's top); infinity without one (hasHolder).
    double holderBottom() const { return holderBottom_; }
    double cuttingLength() const { return cuttingLength_; }
    double maxRadius() const { return maxRadius_; }
    /// @brief The largest radius at or below the cutting length (half the cutting diameter).
    double cuttingRadius() const { return cuttingRadius_; }

    /// @brief The profile radius R(z) at height z above the tip; where R jumps between pieces, the
    /// larger side. Negative when z is outside [bottom, totalLength].
    double radiusAt(double z) const;

    /// @brief Point membership in the tool frame: axial height z, distance rho from the axis.
    bool containsLocal(double rho, double z) const;
    /// @brief Point membership of a world point for a tool at `pose`.
    bool contains(const ToolPose& pose, const Vec3& p) const;

    /// @brief The material intervals of `line` (unit direction) inside the tool at `pose`, as line
    /// parameters: sorted, disjoint, at most one per convex part. Exact up to rounding.
    std::vector<Interval> intersect(const ToolPose& pose, const Line& line) const;
    /// @brief The interval of a line (in tool-frame form) inside one convex part.
    Interval intersectPart(const ConvexPart& part, const LocalLine& line) const;

    /// @brief The part of the tool between heights z0 and z1 (clipped to the tool), as a tool in
    /// the same frame: its tip, the CL point, stays at height 0, so its lowest face is at z0.
    /// `region(cuttingLength(), totalLength())` is the shank, for collision checks.
    /// @throw Error if the clipped range has no height.
    Tool region(double z0, double z1) const;

    /// @brief The lowest height of the solid: 0 for a whole tool, z0 for a region.
    double bottom() const { return bottom_; }

  private:
    std::string description_;
    std::vector<ProfilePiece> pieces_;
    std::vector<ConvexPart> parts_;
    double bottom_ = 0.0;
    double totalLength_ = 0.0;
    double cuttingLength_ = 0.0;
    double maxRadius_ = 0.0;
    double cuttingRadius_ = 0.0;
    double holderBottom_ = std::numeric_limits<double>::infinity();  ///< where a holder starts

    friend Tool withHolder(const Tool& tool, double d, double length);
};

}  // namespace dexelmill
