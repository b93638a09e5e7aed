/// @file roots.h
/// @brief A root of a function of one variable inside a bracket, by Newton's method kept safe by
/// bisection.
#pragma once

#include <algorithm>
#include <cmath>
#include <utility>

namespace dexelmill {

/// Most steps newtonBracket takes. Its steps shrink at least geometrically or bisect, so a
/// bracket of 100 mm closes to 1e-12 mm in about 47 bisections at worst and in a few Newton steps
/// where the root is simple. (Where the doubles near the root are spaced wider than the tolerance,
/// the steps run out: the bracket returned is still valid.)
constexpr int kNewtonBracketSteps = 200;

/// A bracket [lo, hi], at most `tol` wide, of the root of f between x0 and x1, where f has
/// opposite signs (f0, f1) or is 0 at one of them. `f(x, value, slope)` gives f and its
/// derivative, and returns false to stop the search at x, which is then returned as the bracket
/// [x, x]. An end where f is 0 is the root: f is called there, so that a caller sees the point it
/// returns as the last it evaluated, and [x, x] is returned. Newton's steps from
/// the secant's root, each kept only where it lands inside the bracket and is less than half the
/// step before it, else the bracket is bisected (the rule of Numerical Recipes' rtsafe); a step
/// shorter than tol / 2 is lengthened to tol / 2, so that it crosses the root and closes the
/// bracket. Each step's point narrows the bracket by its sign; a value without one (NaN) leaves the
/// bracket as it is and bisects it, so where f stays NaN the steps run out with a bracket wider
/// than tol. With tol 0 the search runs until f stops it or the steps run out.
template <class F>
std::pair<double, double> newtonBracket(F&& f, double x0, double x1, double f0, double f1, double tol) {
    if (f0 == 0.0 || f1 == 0.0) {
        // Else the secant below would start outside the bracket, and the steps leave it.
        const double x = f0 == 0.0 ? x0 : x1;
        double fx = 0.0, dfx = 0.0;
        f(x, fx, dfx);
        return {x, x};
    }
    // neg: an end where f < 0; pos: one where f > 0 (either may be the larger).
    double neg = f0 < 0.0 ? x0 : x1, pos = f0 < 0.0 ? x1 : x0;
    double x = neg - (f0 < 0.0 ? f0 : f1) * (pos - neg) / (f1 < 0.0 ? f0 - f1 : f1 - f0);
    double step = std::abs(pos - neg), lastStep = step;
    for (int k = 0; k < kNewtonBracketSteps && std::abs(pos - neg) > tol; ++k) {
        double fx = 0.0, dfx = 0.0;
        if (!f(x, fx, dfx)) return {x, x};
        if (fx < 0.0) {
            neg = x;
        } else if (fx > 0.0) {
            pos = x;
        } else if (fx == 0.0) {
            return {x, x};
        } else {  // NaN: no sign, so no narrower bracket; bisect it
            x = 0.5 * (neg + pos);
            continue;
        }
        if (std::abs(pos - neg) <= tol) break;
        const double lo = std::min(neg, pos), hi = std::max(neg, pos);
        double next = x - fx / dfx;
        lastStep = step;
        if (!(next > lo && next < hi) || std::abs(2.0 * fx) > std::abs(lastStep * dfx)) {
            next = 0.5 * (lo + hi);
        } else if (std::abs(next - x) < 0.5 * tol) {
            next = x + (next > x ? 0.5 * tol : -0.5 * tol);
            if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        }
        step = std::abs(next - x);
        x = next;
    }
    return std::minmax(neg, pos);
}

}  // namespace dexelmill
