// The torus pieces' grazing curves met by a query line: the guaranteed root finding of a
// MoveSweep query (method.md section 4; the paper's Algorithm 1).
#include <algorithm>
#include <cmath>

#include <boost/math/tools/toms748_solve.hpp>

#include "dexelmill/geometry/tolerance.h"
#include "sweep/parts.h"

namespace dexelmill {

namespace {

/// A root of a function monotone on [a, b] whose values ga = g(a) and gb = g(b) are of opposite
/// signs and not zero: Newton's method with the analytic slope, safeguarded by the sign-change
/// bracket. A Newton step is taken only when it lands strictly inside the bracket and is at most
/// half the step before it; otherwise the bracket is bisected. The first point is `t0` when it
/// lies strictly inside the bracket, else the secant (regula falsi) point. Stops when a step or the
/// bracket is at most `tol`, or when two Newton steps in a row show quadratic convergence that puts
/// the next step below `tol` (the error after a Newton step of size s is about (s / s_before^2) s^2).
/// `gd(t, slope)` returns g(t) and writes g'(t).
///
/// Why not Boost's newton_raphson_iterate (1.74, Debian 12): it moves its bracket by the sign of
/// the Newton step g / g' rather than of g, and raises an error when the two disagree. Near a
/// tangent line the root sits next to an extremum of g, where g' rounds to either sign; a bracket
/// kept by the sign of g, as here, stays valid there. TOMS 748 (Boost) solves the same brackets
/// without the slope; when this replaced it, callgrind counted 2,218 instructions per bull-nose
/// ramp query with TOMS 748 against 1,521 with it.
template <class GD>
double bracketedNewton(GD&& gd, double a, double b, double ga, double gb, double t0, double tol) {
    constexpr int kMaxSteps = 100;  // bisection alone halves a bracket of width 2 to 1e-13 in 45
    double neg = ga < 0.0 ? a : b, pos = ga < 0.0 ? b : a;  // g(neg) < 0 < g(pos)
    double t = t0;
    if (!(t > std::min(a, b) && t < std::max(a, b))) t = a - ga * (b - a) / (gb - ga);
    if (!(t > std::min(a, b) && t < std::max(a, b))) t = 0.5 * (a + b);
    double step = std::abs(b - a), stepBefore = 2.0 * step;
    bool newtonBefore = false;
    for (int i = 0; i < kMaxSteps; ++i) {
        double slope;
        const double g = gd(t, slope);
        if (g == 0.0) return t;
        (g < 0.0 ? neg : pos) = t;
        const double newton = t - g / slope;
        const bool inside = slope != 0.0 && newton > std::min(neg, pos) && newton < std::max(neg, pos);
        stepBefore = step;
        const bool isNewton = inside && 2.0 * std::abs(g) <= std::abs(stepBefore * slope);
        if (isNewton) {
            step = std::abs(newton - t);
            t = newton;
            if (newtonBefore && step * step * step <= tol * stepBefore * stepBefore) return t;
        } else {
            t = 0.5 * (neg + pos);
            step = 0.5 * std::abs(pos - neg);
        }
        newtonBefore = isNewton;
        if (step <= tol || std::abs(pos - neg) <= tol) return t;
    }
    return t;
}

}  // namespace

/// Adds the crossings of the line with a torus piece's grazing surface to `ex`.
///
/// Eq. (36): the line meets the sweep of the grazing point G where g = c . (G - o) = 0,
/// c = w x f. Seen along f, the grazing curve is the outline of the torus's shadow and g is the
/// signed distance of its points from the projected line, times |c|. Along that convex outline g
/// has exactly one maximum, where the grazing normal is c / |c|, and one minimum (-c / |c|): so
/// each arc, split at those two points, falls into pieces where g is monotone and every root is
/// bracketed by a sign change. That is Algorithm 1 with its extremum (fminbnd in the paper) in
/// closed form; the roots are found by Newton's method on the bracket (bracketedNewton), with
/// TOMS 748 in the spine chart.
///
/// Two charts of the curve keep the root finder well conditioned:
///  - the normal angle psi, N(psi) = cos(psi) q + sin(psi) e, on most of the curve;
///  - the spine angle s (the paper's parameter, Eq. 34), N(s) ~ (|fn| cos s, |fn| sin s,
///    -sign(fn) fd cos s), near the d-n plane, on moves with kappa = |fn| / |f| < kSpineChart.
///    On a nearly horizontal move that stretch of the curve runs along the torus's bottom (or
///    top) circle but is squeezed into a psi-window of width about kappa: the spine azimuth s
///    turns by cos^2(s) / kappa per unit of psi. The charts meet where |sin psi| = sqrt(kappa)
///    |cos psi|, at |cos s| = sqrt(kappa) (about): there s turns by about one unit per unit of
///    psi, and the grazing point's climb up the torus as |cos s| falls, rho kappa / cos^2(s) per
///    unit of s, is at most about rho. With the charts meeting at 45 degrees instead, a root found to
///    kAngleRoot in psi was off by kAngleRoot / (2 kappa) in s: 2e-6 mm at kappa = 5e-9.
template <class Ex>
void torusCrossings(const GrazingTorus& tor, std::uint32_t index, const TorusLine& l, Ex& ex) {
    const double fd = l.f.x, fn = l.f.z;
    const double flen = std::sqrt(fd * fd + fn * fn);
    const double kappa = std::abs(fn) / flen;
    const Vec3 qDir(-fn / flen, 0.0, fd / flen);
    const double cLen = std::sqrt(l.c2);
    const double cq = glm::dot(l.c, qDir) / cLen, ce = l.c.y / cLen;  // c / |c| = cq q + ce e
    const double sgnFn = fn > 0.0 ? 1.0 : -1.0;

    // The crossing (v, u) of the line with the sweep of the grazing point G:
    // G - o = v w - u f, so v = ((G - o) x f) . c / |c|^2 and u = ((G - o) x w) . c / |c|^2.
    auto addCrossing = [&](const Vec3& g) {
        const Vec3 go = g - l.o;
        ex.add(glm::dot(glm::cross(go, l.f), l.c) / l.c2, glm::dot(glm::cross(go, l.w), l.c) / l.c2,
               Source::of(Source::Torus, index));
    };
    const auto stop = [](double a, double b) { return std::abs(b - a) <= sweep_tol::kAngleRoot; };
    // A root of a monotone piece of g on [a, b] (values ga, gb), or nothing.
    auto solve = [&](auto&& g, double a, double b, double ga, double gb, double& root) {
        if (ga == 0.0) return root = a, true;
        if (gb == 0.0) return root = b, true;
        if ((ga < 0.0) == (gb < 0.0)) return false;
        boost::uintmax_t iters = 80;
        const auto br = boost::math::tools::toms748_solve(g, a, b, ga, gb, stop, iters);
        root = 0.5 * (br.first + br.second);
        return true;
    };
    // Spine chart: the grazing point at the azimuth (cs, ss) of its normal (a unit vector).
    auto spinePoint = [&](double cs, double ss) {
        const double inv = 1.0 / std::sqrt(fn * fn + fd * fd * cs * cs);
        const double nr = std::abs(fn) * inv;
        return Vec3((tor.rc + tor.rho * nr) * cs, (tor.rc + tor.rho * nr) * ss,
                    tor.zc - sgnFn * tor.rho * fd * cs * inv);
    };
    const bool useSpine = kappa < sweep_tol::kSpineChart;
    const double chartSlope = std::sqrt(kappa);  // the charts meet where |sin psi| = this |cos psi|
    for (int k = 0; k < tor.arcs; ++k) {
        const TorusArc& arc = tor.arc[k];
        // Normal-angle chart: psi = psiMid + 2 atan(t).
        auto normal = [&](double t, double& cp, double& sp) {
            const double t2 = t * t, den = 1.0 / (1.0 + t2);
            const double cd = (1.0 - t2) * den, sd = 2.0 * t * den;
            cp = arc.cosMid * cd - arc.sinMid * sd;
            sp = arc.sinMid * cd + arc.cosMid * sd;
        };
        auto point = [&](double t) {
            double cp, sp;
            normal(t, cp, sp);
            return torusPoint(tor, -fn * cp / flen, sp, fd * cp / flen);
        };
        auto g = [&](double t) { return glm::dot(l.c, point(t)) - l.co; };
        // g and dg/dt: with dpsi/dt = 2 / (1 + t^2), the grazing point P = k Nxy + (0, 0, zc + rho Nz)
        // (k = rc / |Nxy| + rho, Nxy the normal's part across the axis) moves by
        // dP/dpsi = dk Nxy + k dNxy/dpsi + rho dNz/dpsi, dk = -rc (Nxy . dNxy/dpsi) / |Nxy|^3.
        auto gSlope = [&](double t, double& slope) {
            double cp, sp;
            normal(t, cp, sp);
            const double nx = -fn * cp / flen, nz = fd * cp / flen;
            const double dnx = fn * sp / flen, dnz = -fd * sp / flen;  // dny/dpsi = cp
            const double nr2 = nx * nx + sp * sp, nr = std::sqrt(nr2);
            const double k = tor.rc / nr + tor.rho;
            const double dk = -tor.rc * (nx * dnx + sp * cp) / (nr2 * nr);
            const Vec3 p(k * nx, k * sp, tor.zc + tor.rho * nz);
            const Vec3 dp(dk * nx + k * dnx, dk * sp + k * cp, tor.rho * dnz);
            slope = glm::dot(l.c, dp) * 2.0 / (1.0 + t * t);
            return glm::dot(l.c, p) - l.co;
        };
        // t of a normal direction (cos psi, sin psi) inside the arc.
        auto tOf = [&](double cx, double sy) {
            const double cosD = cx * arc.cosMid + sy * arc.sinMid;
            const double sinD = sy * arc.cosMid - cx * arc.sinMid;
            return std::clamp(sinD / (1.0 + cosD), -arc.T, arc.T);
        };
        auto inArc = [&](double cx, double sy) {
            return arc.side * sy >= 0.0 && cx >= tor.cosLo && cx <= tor.cosHi;
        };

        // Split points: the extrema of g (N = +-c/|c|) and the chart boundaries |sin psi| =
        // sqrt(kappa) |cos psi|.
        double ts[6];
        bool extremum[6] = {};
        int m = 0;
        ts[m++] = -arc.T;
        for (double sgn : {1.0, -1.0})
            if (inArc(sgn * cq, sgn * ce)) extremum[m] = true, ts[m++] = tOf(sgn * cq, sgn * ce);
        if (useSpine) {
            const double cw = 1.0 / std::sqrt(1.0 + chartSlope * chartSlope), sw = chartSlope * cw;
            for (double sgn : {1.0, -1.0})
                if (inArc(sgn * cw, arc.side * sw)) ts[m++] = tOf(sgn * cw, arc.side * sw);
        }
        ts[m++] = arc.T;
        for (int i = 2; i + 1 < m; ++i)  // insertion sort of the (at most 4) inner points
            for (int j = i; j > 1 && ts[j - 1] > ts[j]; --j) {
                std::swap(ts[j - 1], ts[j]);
                std::swap(extremum[j - 1], extremum[j]);
            }

        // A first guess at the root of a piece from an extremum te of g (value ge) to tb (value
        // gb): fit g = A + B cos(psi - psi_e), exact for a sphere's outline (a circle) and close
        // for a torus's, and solve it. Not a bracket: bracketedNewton checks it lies inside.
        auto fittedRoot = [&](double te, double tb, double ge, double gb) {
            double ce0, se0, cb0, sb0;
            normal(te, ce0, se0);
            normal(tb, cb0, sb0);
            const double cosD = ce0 * cb0 + se0 * sb0, sinD = ce0 * sb0 - se0 * cb0;
            const double B = (ge - gb) / (1.0 - cosD);
            const double cr = std::clamp((B - ge) / B, -1.0, 1.0);  // cos(psi_root - psi_e) = -A / B
            const double sr = std::copysign(std::sqrt(1.0 - cr * cr), sinD);
            return tOf(ce0 * cr - se0 * sr, se0 * cr + ce0 * sr);
        };

        double gPrev = glm::dot(l.c, arc.endLo) - l.co;
        for (int i = 0; i + 1 < m; ++i) {
            const double ta = ts[i], tb = ts[i + 1];
            const double gb = i + 2 == m ? glm::dot(l.c, arc.endHi) - l.co : g(tb);
            const double ga = gPrev;
            gPrev = gb;
            if (!(tb > ta) && !(ga == 0.0)) continue;
            double cp, sp;
            normal(0.5 * (ta + tb), cp, sp);
            const bool spineChart = useSpine && std::abs(sp) < chartSlope * std::abs(cp);
            double root;
            if (!spineChart) {
                if (ga == 0.0) {
                    addCrossing(point(ta));
                } else if (gb == 0.0) {
                    addCrossing(point(tb));
                } else if ((ga < 0.0) != (gb < 0.0)) {
                    const double t0 = extremum[i]       ? fittedRoot(ta, tb, ga, gb)
                                      : extremum[i + 1] ? fittedRoot(tb, ta, gb, ga)
                                                        : kInf;
                    addCrossing(point(bracketedNewton(gSlope, ta, tb, ga, gb, t0, sweep_tol::kAngleRoot)));
                }
                continue;
            }
            // The same stretch in the spine chart, parametrised without trigonometry by the
            // direction a(tau) ~ a0 + tau (a1 - a0), tau in [0, 1], between the azimuths a0, a1 of
            // the normals at its ends (less than 90 degrees apart, so a is monotone in angle).
            // The bracket keeps the values of g the neighbouring pieces saw at its ends.
            double c0, s0, c1, s1;
            normal(ta, c0, s0);
            normal(tb, c1, s1);
            const double ax0 = -fn * c0 / flen, ay0 = arc.side * std::abs(s0);
            const double ax1 = -fn * c1 / flen, ay1 = arc.side * std::abs(s1);
            auto spineAt = [&](double tau) {
                const double x = ax0 + tau * (ax1 - ax0), y = ay0 + tau * (ay1 - ay0);
                const double inv = 1.0 / std::sqrt(x * x + y * y);
                return spinePoint(x * inv, y * inv);
            };
            auto gSpine = [&](double tau) { return glm::dot(l.c, spineAt(tau)) - l.co; };
            if (solve(gSpine, 0.0, 1.0, ga, gb, root)) addCrossing(spineAt(root));
        }
    }
}

template void torusCrossings<Extremes<false>>(const GrazingTorus&, std::uint32_t, const TorusLine&, Extremes<false>&);
template void torusCrossings<Extremes<true>>(const GrazingTorus&, std::uint32_t, const TorusLine&, Extremes<true>&);

}  // namespace dexelmill
