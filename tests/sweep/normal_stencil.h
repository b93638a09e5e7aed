// The tangent plane of a swept volume S at an end of a line's interval, by finite differences of
// S's boundary, for the turning sweeps' normal tests (turning_normals_test.cpp,
// rotary_sweep_oracle_test.cpp). S is given by a membership test alone.
//
// The line offset by `step` along two unit vectors a, b across it, both ways, meets S's boundary
// at P(+-a), P(+-b); P(+a) - P(-a) and P(+b) - P(-b) span the tangent plane (central differences,
// error of order step^2 times the squared curvature). n(+) from P(+a) - P(0) and P(+b) - P(0) and
// n(-) from P(0) - P(-a) and P(0) - P(-b) differ by the turn: about step times the curvature on a
// smooth surface, as large as the crease's angle where the end lies within step of a crease.
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>

#include "dexelmill/geometry/types.h"

namespace stencil {

using dexelmill::Interval;
using dexelmill::Line;
using dexelmill::Vec3;

/// Halvings of brackets under 1 mm: below 1e-13 mm.
constexpr int kBisect = 45;

/// A larger turn across a stencil: a crease (rad).
constexpr double kCreaseTurn = 0.05;

/// The step of the wide stencil that looks for a crease near an end marked sharp, in tolerances:
/// twice the solver's rim reach (4 epsilon), which marks ends that near a crease sharp.
constexpr double kSharpReach = 8.0;

/// The shallowest crease creaseBetween tells from curvature (rad): far above the stencils'
/// rounding (their points are bisected to ~1e-13 mm, 1e-9 rad over 1e-4 mm), and the solver's own
/// least angle between two faces at a rim.
constexpr double kLeastCrease = 1e-4;

inline double angle(const Vec3& a, const Vec3& b) {
    return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

/// S's boundary on `line` between a parameter inside S and one outside: bisection on
/// `in(point)`. Empty when the two are not on either side.
template <class In>
std::optional<double> boundary(const In& in, const Line& line, double inside, double outside) {
    if (!in(line.at(inside)) || in(line.at(outside))) return {};
    for (int i = 0; i < kBisect; ++i) {
        const double mid = 0.5 * (inside + outside);
        (in(line.at(mid)) ? inside : outside) = mid;
    }
    return 0.5 * (inside + outside);
}

/// An end of a line's interval, and the bracket its stencils are bisected in.
struct End {
    double v;        ///< the end's parameter on the line
    double sense;    ///< outward along the line: +1 at the upper end, -1 at the lower
    double inside;   ///< inside the interval: half way in, at most `reach` from v
    double outside;  ///< outside it: `reach` past v
};

/// The upper end of `range` (`upper`) or its lower, bracketed to within `reach` of it.
inline End bracket(const Interval& range, bool upper, double reach) {
    const double v = upper ? range.hi : range.lo, sense = upper ? 1.0 : -1.0;
    return {v, sense, v - sense * std::min(0.5 * range.length(), reach), v + sense * reach};
}

/// Two unit vectors across `dir` and across each other.
inline void across(const Vec3& dir, Vec3& a, Vec3& b) {
    a = glm::normalize(glm::cross(dir, std::abs(dir.x) < 0.6 ? Vec3(1, 0, 0) : Vec3(0, 1, 0)));
    b = glm::cross(dir, a);
}

/// The boundary points on `line` and on the lines offset by `step` along +-a and +-b (p[0],
/// p[1 .. 2], p[3 .. 4]), bisected between parameters `inside` and `outside`; false when one is
/// not bracketed.
template <class In>
bool points(const In& in, const Line& line, double step, double inside, double outside, Vec3 p[5]) {
    Vec3 a, b;
    across(line.dir, a, b);
    const Vec3 offsets[5] = {Vec3(0.0), a, -a, b, -b};
    for (int j = 0; j < 5; ++j) {
        const Line offset{line.origin + step * offsets[j], line.dir};
        const std::optional<double> end = boundary(in, offset, inside, outside);
        if (!end) return false;
        p[j] = offset.at(*end);
    }
    return true;
}

/// The central difference normal, pointing along `outward`.
inline Vec3 central(const Vec3 p[5], const Vec3& outward) {
    const Vec3 n = glm::normalize(glm::cross(p[1] - p[2], p[3] - p[4]));
    return glm::dot(n, outward) < 0.0 ? -n : n;
}

/// The angle between the one-sided normals n(+) and n(-).
inline double turn(const Vec3 p[5]) {
    return angle(glm::cross(p[1] - p[0], p[3] - p[0]), glm::cross(p[0] - p[2], p[0] - p[4]));
}

/// What the stencil about an end reads of S: its five boundary points (points), its central
/// difference normal, outward, and its turn.
struct Reading {
    Vec3 p[5];
    Vec3 normal;
    double turn = 0.0;
};

/// The stencil of step `step` about end `e` of `line`; empty when a point is not bracketed.
template <class In>
std::optional<Reading> read(const In& in, const Line& line, double step, const End& e) {
    Reading r;
    if (!points(in, line, step, e.inside, e.outside, r.p)) return {};
    r.normal = central(r.p, e.sense * line.dir);
    r.turn = turn(r.p);
    return r;
}

/// Whether a crease of S lies within the wide stencil's reach, from the turns across a narrow
/// stencil and a wide one (`ratio` times as wide). Where S is smooth, its one-sided normals turn
/// by its curvature times the step, so the wide turn is about `ratio` times the narrow. A crease
/// within both gives both its angle; one beyond the narrow stencil's reach gives the wide stencil
/// its angle and the narrow one curvature alone. So a wide turn of at least kLeastCrease that is
/// at most twice the narrow, or at least twice `ratio` times it, is a crease (or a curvature that
/// grows more than twice across the wide stencil). Measured over 31 seeds of the turning normals
/// tests (the families' seeds offset by 7919 k, k = 0 to 30): of the 11 ends marked sharp that
/// kCreaseTurn alone took as wrong, 9 are so told, with wide turns of 9.6e-4 to 0.048 rad. The
/// other 2, at a tolerance of 0.01 mm, turn in proportion to the step (narrow 2.4e-5 and 7.1e-6,
/// wide 0.0115 and 0.0057 rad across 0.08 mm): no crease, and they fail.
inline bool creaseBetween(double narrow, double wide, double ratio) {
    return wide > kCreaseTurn || (wide >= kLeastCrease && (wide <= 2.0 * narrow || wide >= 2.0 * ratio * narrow));
}

/// Whether end `e` of `line`, whose narrow stencil (step `narrowStep`) turned by `narrowTurn`,
/// lies within the reach of a crease of S: the stencil of step `wideStep` bends (creaseBetween),
/// or one of its lines falls off an edge of S (its end leaves e's bracket widened outward by four
/// steps). Sets `wideTurn`, or 0 where the wide stencil is not bracketed.
template <class In>
bool creaseNear(const In& in, const Line& line, double narrowStep, double narrowTurn, double wideStep, const End& e,
                double& wideTurn) {
    Vec3 wide[5];
    wideTurn = 0.0;
    if (!points(in, line, wideStep, e.inside, e.outside + e.sense * 4.0 * wideStep, wide)) return true;
    wideTurn = turn(wide);
    return creaseBetween(narrowTurn, wideTurn, wideStep / narrowStep);
}

}  // namespace stencil
