// The box of a move whose tool axis turns (turning.h): the tip's segment box plus the exact box of
// the tool turning on its great circle, or for a machine's rotary move, sampled poses padded by
// the law's acceleration bound.
#include <algorithm>
#include <cmath>
#include <limits>
#include <variant>

#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"
#include "dexelmill/path/motion.h"
#include "dexelmill/sweep/turning.h"

namespace dexelmill {

namespace {

constexpr double kPi = 3.14159265358979323846;

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

/// The box of the tool at one pose.
Box poseBox(const ToolPose& p, const ToolReach& reach) {
    Box box;
    box.expand(p.tip);
    for (int i = 0; i < 3; ++i) {
        box.lo[i] -= reach.along(-p.axis[i], -p.axis[i]);
        box.hi[i] += reach.along(p.axis[i], p.axis[i]);
    }
    return box;
}

/// Most poses the box of a machine's rotary move is sampled at.
constexpr int kMaxBoxSamples = 4096;

/// How far (mm) the box of a machine's rotary move may reach beyond the tool at its poses: far
/// below any lattice's spacing.
constexpr double kBoxPadding = 1e-3;

}  // namespace

ToolReach::ToolReach(double bottom, double length, double radius)
    : terms_{{bottom, radius, 0.0, -1.0, 1.0}, {length, radius, 0.0, -1.0, 1.0}},
      extent_(std::hypot(std::max(std::abs(bottom), std::abs(length)), radius)) {}

ToolReach::ToolReach(const Tool& tool)
    : extent_(std::hypot(std::max(std::abs(tool.bottom()), std::abs(tool.totalLength())), tool.maxRadius())) {
    for (const ProfilePiece& piece : tool.pieces()) {
        for (const double z : {pieceZ0(piece), pieceZ1(piece)})
            terms_.push_back({z, pieceRadius(piece, z), 0.0, -1.0, 1.0});
        if (const auto* arc = std::get_if<ArcPiece>(&piece)) {
            // The outward normal at height z is (R(z) - rc, z - zc) / rho: its c runs from the
            // lower end's to the upper end's.
            const double cLo = (arc->z0 - arc->zc) / arc->rho, cHi = (arc->z1 - arc->zc) / arc->rho;
            terms_.push_back({arc->zc, arc->rc, arc->rho, cLo, cHi});
        }
    }
}

double ToolReach::along(double lo, double hi) const {
    // A unit vector's coordinate rounded past 1 would leave every term out.
    lo = std::clamp(lo, -1.0, 1.0), hi = std::clamp(hi, -1.0, 1.0);
    double best = -std::numeric_limits<double>::infinity();
    for (const Term& t : terms_) {
        const double from = std::max(lo, t.cLo), to = std::min(hi, t.cHi);
        if (from > to) continue;
        const double size = std::hypot(t.s, t.r);
        const double c = std::clamp(size > 0.0 ? t.s / size : 0.0, from, to);
        best = std::max(best, t.s * c + t.r * std::sqrt(std::max(0.0, 1.0 - c * c)) + t.d);
    }
    return best;
}

double turnAngle(const Move& m) {
    if (!m.turns()) return 0.0;
    return std::atan2(glm::length(glm::cross(*m.startAxis, m.axis)), glm::dot(*m.startAxis, m.axis));
}

Box turningMoveBox(const Move& m, double bottom, double length, double radius) {
    return turningMoveBox(m, ToolReach(bottom, length, radius));
}

Box turningMoveBox(const Move& m, const ToolReach& reach) {
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
        const double accel = law.axisPointAccelerationBound(reach.extent());
        const int n = int(std::clamp(std::ceil(std::sqrt(accel / (8.0 * kBoxPadding))), 1.0, double(kMaxBoxSamples)));
        Box box;
        for (int k = 0; k <= n; ++k) {
            const Box b = poseBox(law.pose(double(k) / n), reach);
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
        box.lo[i] -= reach.along(-hi, -lo);
        box.hi[i] += reach.along(lo, hi);
    }
    return box;
}

}  // namespace dexelmill
