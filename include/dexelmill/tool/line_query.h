/// @file line_query.h
/// @brief A line seen from a tool, and its interval inside one profile piece: the closed forms for
/// cones, cylinders and spheres, inline because the sweep's end-pose queries run them per dexel.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <variant>

#include "dexelmill/geometry/types.h"
#include "dexelmill/tool/profile.h"

namespace dexelmill {

/// @brief Where a tool is: the tip (cutter-location point) and the unit axis along which the tool
/// extends from its tip.
struct ToolPose {
    Vec3 tip{0.0};
    Vec3 axis{0.0, 0.0, 1.0};
};

/// @brief A line expressed in a tool's frame. Along the line, with parameter t = v - vShift,
///   height above the tip   z(t)     = z0 + zv t
///   squared axis distance  rho^2(t) = A t^2 + 2 B t + C.
/// `vShift` is the parameter of the line point nearest the tip, so that the coefficients stay
/// small however far the line's origin is from the tool.
struct LocalLine {
    double z0 = 0.0, zv = 0.0;
    double A = 0.0, B = 0.0, C = 0.0;
    double vShift = 0.0;

    /// @brief The line `line` (unit direction) seen from a tool at `pose`.
    static LocalLine make(const ToolPose& pose, const Line& line);
};

namespace detail {

/// The (at most two) intervals where a t^2 + 2 b t + c <= 0.
struct QuadSolution {
    Interval first, second;
};

inline QuadSolution solveQuadraticLE(double a, double b, double c) {
    QuadSolution out;
    if (a == 0.0) {
        if (b == 0.0) {
            if (c <= 0.0) out.first = Interval::all();
        } else if (b > 0.0) {
            out.first = {-std::numeric_limits<double>::infinity(), -c / (2.0 * b)};
        } else {
            out.first = {-c / (2.0 * b), std::numeric_limits<double>::infinity()};
        }
        return out;
    }
    const double disc = b * b - a * c;
    if (disc < 0.0) {
        if (a < 0.0) out.first = Interval::all();
        return out;
    }
    // Stable roots: q = -(b + sign(b) sqrt(disc)); the roots are q / a and c / q.
    const double q = -(b + std::copysign(std::sqrt(disc), b));
    double r1 = q / a;
    double r2 = q != 0.0 ? c / q : r1;
    if (r1 > r2) std::swap(r1, r2);
    if (a > 0.0) {
        out.first = {r1, r2};
    } else {
        out.first = {-std::numeric_limits<double>::infinity(), r1};
        out.second = {r2, std::numeric_limits<double>::infinity()};
    }
    return out;
}

/// The parameter range where the line's height lies in [z0, z1].
inline Interval slabRange(const LocalLine& l, double z0, double z1) {
    if (l.zv == 0.0) return (l.z0 >= z0 && l.z0 <= z1) ? Interval::all() : Interval::empty();
    const double inv = 1.0 / l.zv;
    double t0 = (z0 - l.z0) * inv;
    double t1 = (z1 - l.z0) * inv;
    if (t0 > t1) std::swap(t0, t1);
    return {t0, t1};
}

/// Line inside the cylinder rho <= r, as a parameter range (all, when the line is parallel to the
/// axis and inside).
inline Interval cylinderRange(const LocalLine& l, double r) {
    const QuadSolution s = solveQuadraticLE(l.A, l.B, l.C - r * r);
    return s.first;  // A >= 0, so a single interval
}

// Cone frustum or cylinder: rho(t)^2 <= (alpha + beta t)^2 with alpha + beta t >= 0.
inline Interval intersectCone(const ConePiece& c, const LocalLine& l) {
    const Interval slab = slabRange(l, c.z0, c.z1);
    if (slab.isEmpty()) return slab;
    if (c.r0 == c.r1) return cylinderRange(l, c.r0).intersect(slab);
    const double k = (c.r1 - c.r0) / (c.z1 - c.z0);
    const double alpha = c.r0 + k * (l.z0 - c.z0);
    const double beta = k * l.zv;
    const QuadSolution s =
        solveQuadraticLE(l.A - beta * beta, l.B - alpha * beta, l.C - alpha * alpha);
    // The valid nappe: R(z(t)) = alpha + beta t >= 0.
    Interval nappe = Interval::all();
    if (beta > 0.0) nappe.lo = -alpha / beta;
    if (beta < 0.0) nappe.hi = -alpha / beta;
    const Interval range = slab.intersect(nappe);
    const Interval p1 = s.first.intersect(range);
    const Interval p2 = s.second.intersect(range);
    if (p2.isEmpty()) return p1;
    if (p1.isEmpty()) return p2;
    // Both pieces survive only when the line passes through the apex, where one of them shrinks
    // to a point: keep the longer.
    return p1.length() >= p2.length() ? p1 : p2;
}

// Sphere slab: rho^2 + (z - zc)^2 <= rho_s^2.
inline Interval intersectSphere(const ArcPiece& a, const LocalLine& l, const Interval& slab) {
    const double dz = l.z0 - a.zc;
    const QuadSolution s =
        solveQuadraticLE(l.A + l.zv * l.zv, l.B + dz * l.zv, l.C + dz * dz - a.rho * a.rho);
    return s.first.intersect(slab);
}

/// The torus slab, by bracketed root finding (tool.cpp).
Interval intersectTorus(const ArcPiece& a, const LocalLine& l, const Interval& slab);

/// An interval that holds the torus slab's and whose ends lie within `slack` of its ends along the
/// line (at least tol::kRoot): the same root finding, stopped sooner, with each end taken from
/// the outer side of its bracket. `near` (possibly empty) is a hint, an interval whose ends are
/// likely inside the torus by about `reach` (local parameters): the root finding starts there,
/// and the result does not depend on it.
Interval outerTorusInterval(const ArcPiece& a, const LocalLine& l, const Interval& slab, double slack,
                            const Interval& near = Interval::empty(), double reach = 0.0);

/// The torus slab's interval where a closed form gives it (a line along the axis, at a constant
/// height, missing the slab's outer cylinder, or inside at both ends of its range there): returns
/// true and sets `out`; false where intersectTorus needs its root finding.
bool torusClosedForm(const ArcPiece& a, const LocalLine& l, const Interval& slab, Interval& out);

}  // namespace detail

/// @brief The outward unit normal of a piece's lateral surface at its point at distance `rho` from
/// the axis and height `z`, in the meridian half-plane: `nr` across the axis (away from it), `nz`
/// along it. A cone's is the same all along a generator, (1, -dR/dz) normalised; an arc's points
/// from its circle's centre (rc, zc) to the point, which lies on the outer half (rho >= rc).
inline void meridianNormal(const ProfilePiece& piece, double rho, double z, double& nr, double& nz) {
    if (const auto* c = std::get_if<ConePiece>(&piece)) {
        const double dr = c->r1 - c->r0, dz = c->z1 - c->z0;
        const double inv = 1.0 / std::sqrt(dr * dr + dz * dz);
        nr = dz * inv;
        nz = -dr * inv;
        return;
    }
    const ArcPiece& a = std::get<ArcPiece>(piece);
    const double mr = std::max(0.0, rho - a.rc), mz = z - a.zc;
    const double len = std::sqrt(mr * mr + mz * mz);
    if (len == 0.0) {  // the circle's centre: no point of the surface; the equator's normal
        nr = 1.0, nz = 0.0;
        return;
    }
    nr = mr / len;
    nz = mz / len;
}

/// @brief The interval of the line inside one piece's slab solid { z in [z0, z1], rho <= R(z) }.
/// Cones, cylinders and spheres in closed form; the torus by bracketed root finding on the convex
/// function rho(t) - R(z(t)) (Newton's method on a smooth function of its sign, or TOMS 748).
inline Interval intersectPiece(const ProfilePiece& piece, const LocalLine& line) {
    if (const auto* c = std::get_if<ConePiece>(&piece)) return detail::intersectCone(*c, line);
    const ArcPiece& a = std::get<ArcPiece>(piece);
    const Interval slab = detail::slabRange(line, a.z0, a.z1);
    if (slab.isEmpty()) return slab;
    return a.rc == 0.0 ? detail::intersectSphere(a, line, slab)
                       : detail::intersectTorus(a, line, slab);
}

}  // namespace dexelmill
