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

#include <cmath>
#include <optional>

#include "dexelmill/geometry/types.h"

namespace stencil {

using dexelmill::Line;
using dexelmill::Vec3;

/// Halvings of brackets under 1 mm: below 1e-13 mm.
constexpr int kBisect = 45;

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

}  // namespace stencil
