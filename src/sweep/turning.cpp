#include "dexelmill/sweep/turning.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"

namespace dexelmill {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// The largest g(c) = length max(c, 0) + radius sqrt(1 - c^2) over c in [lo, hi] (turning.h).
double reachAlong(double lo, double hi, double length, double radius) {
    const double peak = length / std::hypot(length, radius);
    double best = -std::numeric_limits<double>::infinity();
    for (const double c : {lo, hi, 0.0, peak}) {
        if (c < lo || c > hi) continue;
        best = std::max(best, length * std::max(c, 0.0) + radius * std::sqrt(std::max(0.0, 1.0 - c * c)));
    }
    return best;
}

}  // namespace

double turnAngle(const Move& m) {
    if (!m.turns()) return 0.0;
    return std::atan2(glm::length(glm::cross(*m.startAxis, m.axis)), glm::dot(*m.startAxis, m.axis));
}

Box turningMoveBox(const Move& m, double length, double radius) {
    const Vec3 a0 = m.turns() ? *m.startAxis : m.axis;
    const double theta = turnAngle(m);
    const Vec3 across = m.axis - glm::dot(m.axis, a0) * a0;
    if (glm::dot(a0, m.axis) < 0.0 && glm::length(glm::cross(a0, m.axis)) <= tol::kParallel)
        throw Error("the axes are opposite: no one great circle joins them");
    const double acrossLength = glm::length(across);
    const Vec3 b = acrossLength > 0.0 ? across / acrossLength : Vec3(0.0);
    Box box;
    box.expand(m.start);
    box.expand(m.end);
    for (int i = 0; i < 3; ++i) {
        double lo = std::min(a0[i], m.axis[i]), hi = std::max(a0[i], m.axis[i]);
        const double rho = std::hypot(a0[i], b[i]), phi = std::atan2(b[i], a0[i]);
        for (const double t : {phi, phi + kPi, phi - kPi, phi + 2 * kPi}) {
            if (t < 0.0 || t > theta) continue;
            lo = std::min(lo, rho * std::cos(t - phi));
            hi = std::max(hi, rho * std::cos(t - phi));
        }
        box.lo[i] -= reachAlong(-hi, -lo, length, radius);
        box.hi[i] += reachAlong(lo, hi, length, radius);
    }
    return box;
}

}  // namespace dexelmill
