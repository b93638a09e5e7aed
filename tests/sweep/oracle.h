// Brute-force oracle for the swept volume of a tool on a linear move (method.md section 6).
//
// Shares no code with the solver or with the Tool class's closed forms: the tool is described by
// its own radius-at-height functions, written here from the builders' parameters, one per convex
// part. A point p is removed iff some u in [0, 1] puts p - F(u) inside a part: 0-height within
// [za, zb] and the distance from the axis at most R(z).
//
// Along a line o + v w, with q(u, v) = o + v w - Ps - u f, the function
//   psi(u, v) = |q - (q.n) n| - R(q.n)
// is jointly convex in (u, v) on the convex domain { u in [0, 1], za <= q.n <= zb } because R is
// concave on the part. So Phi(v) = min_u psi(u, v) is convex, and the removed interval is
// { Phi <= 0 }: a golden-section search on u gives Phi(v), a golden-section search on v finds a
// point inside, and bisection finds both ends.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <vector>

#include "dexelmill/geometry/types.h"

namespace oracle {

using dexelmill::Interval;
using dexelmill::Line;
using dexelmill::Vec3;

constexpr double kInf = std::numeric_limits<double>::infinity();

/// One convex part: heights [za, zb] above the tip, radius R(z) (concave), and a bound on R.
struct Part {
    double za = 0.0, zb = 0.0;
    std::function<double(double)> radius;
    double rBound = 0.0;
};

/// A move: tip from ps to ps + f, unit axis n.
struct Motion {
    Vec3 ps{0.0}, f{0.0}, n{0.0, 0.0, 1.0};
};

/// Iterations of the golden-section searches and the bisections. The inner search leaves u known
/// to 0.618^50 ~ 4e-11 of its range; the outer bisection leaves v known to 2^-60 of its range.
constexpr int kInnerGolden = 50;
constexpr int kOuterGolden = 60;
constexpr int kBisect = 60;

/// Phi(v): the least "outside-ness" of the line point at v over the move; +inf when no tool
/// pose of the move reaches the point's height.
inline double phi(const Part& part, const Motion& m, const Line& line, double v) {
    const Vec3 q0 = line.origin + v * line.dir - m.ps;
    const double z0 = glm::dot(q0, m.n), fz = glm::dot(m.f, m.n);
    double ua = 0.0, ub = 1.0;
    if (fz != 0.0) {
        double a = (z0 - part.zb) / fz, b = (z0 - part.za) / fz;
        if (a > b) std::swap(a, b);
        ua = std::max(ua, a), ub = std::min(ub, b);
    } else if (z0 < part.za || z0 > part.zb) {
        return kInf;
    }
    if (ua > ub) return kInf;
    auto psi = [&](double u) {
        const Vec3 q = q0 - u * m.f;
        const double z = std::clamp(glm::dot(q, m.n), part.za, part.zb);
        const Vec3 radial = q - glm::dot(q, m.n) * m.n;
        return glm::length(radial) - part.radius(z);
    };
    // Golden section on the convex psi, keeping the best point seen (ends included).
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    double a = ua, b = ub;
    double best = std::min(psi(a), psi(b));
    double x1 = b - g * (b - a), x2 = a + g * (b - a);
    double f1 = psi(x1), f2 = psi(x2);
    for (int i = 0; i < kInnerGolden; ++i) {
        if (f1 <= f2) {
            b = x2, x2 = x1, f2 = f1;
            x1 = b - g * (b - a), f1 = psi(x1);
        } else {
            a = x1, x1 = x2, f1 = f2;
            x2 = a + g * (b - a), f2 = psi(x2);
        }
    }
    return std::min({best, f1, f2});
}

/// The removed interval of one part along the line (unit direction). `hint`: a parameter to try
/// as an inside point when the search finds none (e.g. the midpoint of a claimed interval); it
/// only seeds the search, both ends are still found by bisection on Phi.
inline Interval removed(const Part& part, const Motion& m, const Line& line, double hint = kInf) {
    // Parameter range: the line inside a ball that holds the whole sweep, and where some pose of
    // the move reaches the line point's height.
    const Vec3 centre = m.ps + 0.5 * m.f + 0.5 * (part.za + part.zb) * m.n;
    const double radius = 0.5 * glm::length(m.f) + std::hypot(part.rBound, 0.5 * (part.zb - part.za)) + 1.0;
    const double t0 = glm::dot(centre - line.origin, line.dir);
    const Vec3 off = line.origin + t0 * line.dir - centre;
    const double d2 = glm::dot(off, off);
    if (d2 >= radius * radius) return Interval::empty();
    const double half = std::sqrt(radius * radius - d2);
    double va = t0 - half, vb = t0 + half;
    const double z0 = glm::dot(line.origin - m.ps, m.n), wz = glm::dot(line.dir, m.n), fz = glm::dot(m.f, m.n);
    const double zLo = part.za + std::min(0.0, fz), zHi = part.zb + std::max(0.0, fz);
    if (wz != 0.0) {
        double a = (zLo - z0) / wz, b = (zHi - z0) / wz;
        if (a > b) std::swap(a, b);
        va = std::max(va, a), vb = std::min(vb, b);
    } else if (z0 < zLo || z0 > zHi) {
        return Interval::empty();
    }
    if (va > vb) return Interval::empty();

    auto P = [&](double v) { return phi(part, m, line, v); };
    // Golden section for an inside point (Phi is convex in v).
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    double a = va, b = vb;
    double x1 = b - g * (b - a), x2 = a + g * (b - a);
    double f1 = P(x1), f2 = P(x2);
    for (int i = 0; i < kOuterGolden && !(std::min(f1, f2) <= 0.0); ++i) {
        if (f1 <= f2) {
            b = x2, x2 = x1, f2 = f1;
            x1 = b - g * (b - a), f1 = P(x1);
        } else {
            a = x1, x1 = x2, f1 = f2;
            x2 = a + g * (b - a), f2 = P(x2);
        }
    }
    double vIn = f1 <= f2 ? x1 : x2;
    double fIn = std::min(f1, f2);
    for (double v : {va, vb, hint}) {
        if (!(fIn <= 0.0) && std::isfinite(v) && v >= va && v <= vb) {
            const double fv = P(v);
            if (fv < fIn) vIn = v, fIn = fv;
        }
    }
    if (!(fIn <= 0.0)) return Interval::empty();

    Interval out{va, vb};
    if (P(va) > 0.0) {
        double outside = va, inside = vIn;
        for (int i = 0; i < kBisect; ++i) {
            const double mid = 0.5 * (outside + inside);
            (P(mid) <= 0.0 ? inside : outside) = mid;
        }
        out.lo = 0.5 * (outside + inside);
    }
    if (P(vb) > 0.0) {
        double outside = vb, inside = vIn;
        for (int i = 0; i < kBisect; ++i) {
            const double mid = 0.5 * (outside + inside);
            (P(mid) <= 0.0 ? inside : outside) = mid;
        }
        out.hi = 0.5 * (outside + inside);
    }
    return out;
}

/// The union of the parts' intervals: sorted, merged where they overlap or come within `gap`,
/// dropping pieces shorter than `minLength`.
inline std::vector<Interval> unite(std::vector<Interval> ivs, double gap, double minLength) {
    ivs.erase(std::remove_if(ivs.begin(), ivs.end(), [](const Interval& i) { return i.isEmpty(); }), ivs.end());
    std::sort(ivs.begin(), ivs.end(), [](const Interval& x, const Interval& y) { return x.lo < y.lo; });
    std::vector<Interval> out;
    for (const Interval& iv : ivs) {
        if (!out.empty() && iv.lo <= out.back().hi + gap) out.back().hi = std::max(out.back().hi, iv.hi);
        else out.push_back(iv);
    }
    out.erase(std::remove_if(out.begin(), out.end(), [&](const Interval& i) { return i.length() <= minLength; }),
              out.end());
    return out;
}

/// Scale factor for randomised case counts: the environment variable DEXELMILL_TEST_SCALE
/// (default 1; e.g. 0.1 for sanitizer builds).
inline double testScale() {
    const char* s = std::getenv("DEXELMILL_TEST_SCALE");
    if (!s) return 1.0;
    const double v = std::atof(s);
    return v > 0.0 ? v : 1.0;
}

}  // namespace oracle
