// Three-point interpolation for the turning sweep's disk and cylinder tests
// (turning_linear_search.cpp, note o): the least of the parabola through three samples over their
// span, and the largest of the node polynomial that scales the interpolation remainder.
#pragma once

#include <algorithm>
#include <cmath>

namespace dexelmill::turning {

/// The least, over [u0, u2], of the parabola through (u0, h0), (u1, h1) and (u2, h2), with
/// u0 < u1 < u2, and where it lies: at the vertex where the parabola opens upwards and its vertex
/// lies inside, else at an end.
struct ParabolaLow {
    double u = 0.0, value = 0.0;
};
inline ParabolaLow parabolaLow(double u0, double h0, double u1, double h1, double u2, double h2) {
    // Newton's form: P(u) = h0 + d01 (u - u0) + c2 (u - u0)(u - u1).
    const double d01 = (h1 - h0) / (u1 - u0), d12 = (h2 - h1) / (u2 - u1);
    const double c2 = (d12 - d01) / (u2 - u0);
    ParabolaLow low = h0 <= h2 ? ParabolaLow{u0, h0} : ParabolaLow{u2, h2};
    if (c2 > 0.0) {
        const double v = 0.5 * (u0 + u1 - d01 / c2);
        if (v > u0 && v < u2) {
            const double value = h0 + d01 * (v - u0) + c2 * (v - u0) * (v - u1);
            if (value < low.value) low = {v, value};
        }
    }
    return low;
}

/// The largest |(u - u0)(u - u1)(u - u2)| over [u0, u2] (u0 <= u1 <= u2): at a root of its
/// derivative 3u^2 - 2 (u0 + u1 + u2) u + (u0 u1 + u0 u2 + u1 u2), the ends giving 0.
inline double nodePolynomialMax(double u0, double u1, double u2) {
    const double sum = u0 + u1 + u2;
    const double disc = std::sqrt(std::max(0.0, sum * sum - 3.0 * (u0 * u1 + u0 * u2 + u1 * u2)));
    double largest = 0.0;
    for (const double u : {(sum - disc) / 3.0, (sum + disc) / 3.0})
        if (u >= u0 && u <= u2) largest = std::max(largest, std::abs((u - u0) * (u - u1) * (u - u2)));
    return largest;
}

}  // namespace dexelmill::turning
