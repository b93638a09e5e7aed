// The box of a move whose tool axis turns (turning.h): the tip's segment box plus the exact box of
// the cylinder turning on its great circle, or for a machine's rotary move, sampled poses padded
// by the law's speed bound.
#include <algorithm>
#include <cmath>
#include <limits>

#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"
#include "dexelmill/path/motion.h"
#include "dexelmill/sweep/turning.h"

namespace dexelmill {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// The largest g(c) = max(bottom c, length c) + radius sqrt(1 - c^2) over c in [lo, hi]
/// (turning.h): the larger of the two concave functions' largest, each at its peak clamped to
/// the range (a function with s = radius = 0 is 0 everywhere).
double reachAlong(double lo, double hi, double bottom, double length, double radius) {
    double best = -std::numeric_limits<double>::infinity();
    for (const double s : {bottom, length}) {
        const double size = std::hypot(s, radius);
        const double c = std::clamp(size > 0.0 ? s / size : 0.0, lo, hi);
        best = std::max(best, s * c + radius * std::sqrt(std::max(0.0, 1.0 - c * c)));
    }
    return best;
}

/// The great circle a move's axis turns on: a(t) = a0 cos t + b sin t, t in [0, theta], with b the
/// unit tangent at a0 towards the end axis (zero, and theta 0, when the axis does not turn).
struct GreatCircle {
    Vec3 a0{0.0, 0.0, 1.0}, b{0.0};
    double theta = 0.0;
};

GreatCircle greatCircle(const Move& m) {
    GreatCircle c;
    c.a0 = m.turns() ? *m.startAxis : m.axis;
    const Vec3 across = m.axis - glm::dot(m.axis, c.a0) * c.a0;
    const double acrossLength = glm::length(across);
    if (acrossLength > 0.0) {
        c.b = across / acrossLength;
        c.theta = turnAngle(m);
    }
    return c;
}

/// The box of the tool (within `radius` of its axis, heights [bottom, length] above the tip) at
/// one pose.
Box poseBox(const ToolPose& p, double bottom, double length, double radius) {
    Box box;
    box.expand(p.tip);
    for (int i = 0; i < 3; ++i) {
        box.lo[i] -= reachAlong(-p.axis[i], -p.axis[i], bottom, length, radius);
        box.hi[i] += reachAlong(p.axis[i], p.axis[i], bottom, length, radius);
    }
    return box;
}

/// Most poses the box of a machine's rotary move is sampled at.
constexpr int kMaxBoxSamples = 4096;

/// How far (mm) the box of a machine's rotary move may reach beyond the tool at its poses: far
/// below any lattice's spacing.
constexpr double kBoxPadding = 1e-3;

}  // namespace

double turnAngle(const Move& m) {
    if (!m.turns()) return 0.0;
    return std::atan2(glm::length(glm::cross(*m.startAxis, m.axis)), glm::dot(*m.startAxis, m.axis));
}

Box turningMoveBox(const Move& m, double bottom, double length, double radius) {
    if (m.rotary) {
        // Samples at u_k = k / N, both ends among them. Between two neighbours a tool point's path
        // y(u) lies within K / (8 N^2) of its chord (linear interpolation's remainder, with
        // K = MotionLaw::axisPointAccelerationBound bounding |y''| for every point within the
        // tool's reach of the tip), and the chord inside the union of the sampled poses' boxes,
        // which hold its ends: so that union padded by K / (8 N^2) holds every pose. N brings the
        // padding within kBoxPadding, up to kMaxBoxSamples. (Samples at the middles of N pieces,
        // padded by the speed bound's V / (2N), took a box 0.2 mm wider on every side, at 0.1 of
        // a D4 ball's radius, and 4 % more dexels of the impeller were bounded.)
        const MotionLaw law(m);
        const double accel = law.axisPointAccelerationBound(std::hypot(std::max(std::abs(bottom), length), radius));
        const int n = int(std::clamp(std::ceil(std::sqrt(accel / (8.0 * kBoxPadding))), 1.0, double(kMaxBoxSamples)));
        Box box;
        for (int k = 0; k <= n; ++k) {
            const Box b = poseBox(law.pose(double(k) / n), bottom, length, radius);
            box.expand(b.lo);
            box.expand(b.hi);
        }
        return box.padded(accel / (8.0 * double(n) * double(n)));
    }
    const GreatCircle turn = greatCircle(m);
    const Vec3 &a0 = turn.a0, &b = turn.b;
    const double theta = turn.theta;
    if (glm::dot(a0, m.axis) < 0.0 && glm::length(glm::cross(a0, m.axis)) <= tol::kParallel)
        throw Error("the axes are opposite: no one great circle joins them");
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
        box.lo[i] -= reachAlong(-hi, -lo, bottom, length, radius);
        box.hi[i] += reachAlong(lo, hi, bottom, length, radius);
    }
    return box;
}

}  // namespace dexelmill
