/// @file arc.h
/// @brief Splitting circular arcs and helices into chords within a tolerance.
#pragma once

#include <cstddef>
#include <vector>

#include "dexelmill/geometry/types.h"

namespace dexelmill::detail {

/// @brief A circular arc or helix in a plane with unit in-plane axes u, v and normal w = u x v:
/// point(t) = centre + r(t) (cos(a(t)) u + sin(a(t)) v) + h(t) w, with angle a, radius r and
/// height h linear in t from the start values to the end values. A positive sweep turns from u
/// towards v (counter-clockwise seen from +w).
struct ArcSpec {
    Vec3 centre{0.0};
    Vec3 u{1.0, 0.0, 0.0}, v{0.0, 1.0, 0.0}, w{0.0, 0.0, 1.0};
    double startAngle = 0.0;
    double sweep = 0.0;  ///< signed, radians
    double startRadius = 0.0, endRadius = 0.0;
    double startHeight = 0.0, endHeight = 0.0;
};

/// @brief The number of chords so that each chord stays within `tolerance` of the arc:
/// a chord of angle phi on a circle of radius r deviates by the sagitta r (1 - cos(phi / 2)),
/// so phi <= 2 acos(1 - tol / r), and phi <= pi (a chord of a half turn or less lies within its
/// sagitta of its arc; a wider one does not). Returns 0 when more than maxSegments would be needed.
std::size_t arcSegments(double radius, double sweep, double tolerance, std::size_t maxSegments);

/// @brief How far `segments` equal chords of an arc of `radius` turning by `sweep` lie from it:
/// the sagitta of one chord (exact for a circular arc; for a spiral or helix, of the circle of
/// `radius`, the larger radius, as arcSegments takes it), for chords of at most a half turn each.
double chordSag(double radius, double sweep, std::size_t segments);

/// @brief The chord end points of the arc (not the start point), the last being the arc's end.
void arcPoints(const ArcSpec& arc, std::size_t segments, std::vector<Vec3>& out);

}  // namespace dexelmill::detail
