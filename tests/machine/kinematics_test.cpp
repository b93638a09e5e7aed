// Machine kinematics against LinuxCNC's trt kinematics written out here as formulas (its
// xyzac-trt and xyzbc-trt sim configs' offsets), and the G-code reader's rotary moves.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"
#include "dexelmill/machine/kinematics.h"
#include "dexelmill/tool/builders.h"
#include "dexelmill/path/camotics.h"
#include "dexelmill/path/gcode.h"
#include "dexelmill/path/motion.h"
#include "support/scratch.h"
#include "support/trt_kinematics.h"

using namespace dexelmill;
using Catch::Matchers::Contains;
using testing::xyzacAxis;
using testing::xyzacForward;
using testing::xyzbcForward;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

double distance(const Vec3& a, const Vec3& b) { return glm::length(a - b); }

/// A move of xyzac-trt as the bound tests draw it: A within 80 degrees and C within 180 of zero,
/// turning by up to 40 and 120 degrees, the joints within 50 mm of the origin.
struct AcMove {
    RotaryAngles from, to;
    Vec3 j0, j1;

    /// The move on `ac`, under TCP or with identity kinematics.
    Move move(const Machine& ac, bool tcp) const {
        Move m;
        m.start = j0, m.end = j1;
        m.rotary = std::make_shared<const RotaryMotion>(ac.motion(from, to, tcp, j0, j1));
        return m;
    }
    /// The issue's formula for the tool axis, (sin C sin A, cos C sin A, cos A), the angles
    /// linear in u.
    Vec3 axis(double u) const {
        return xyzacAxis(from['A'] + u * (to['A'] - from['A']), from['C'] + u * (to['C'] - from['C']));
    }
};
AcMove randomAcMove(std::mt19937& rng) {
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    AcMove m;
    m.from['A'] = 80 * uni(rng), m.from['C'] = 180 * uni(rng);
    m.to['A'] = m.from['A'] + 40 * uni(rng), m.to['C'] = m.from['C'] + 120 * uni(rng);
    m.j0 = Vec3(50 * uni(rng), 50 * uni(rng), 50 * uni(rng));
    m.j1 = Vec3(50 * uni(rng), 50 * uni(rng), 50 * uni(rng));
    return m;
}

/// A head-table machine: a table C about z through the origin, and a head B about y pivoting
/// 150 mm above the tip.
Machine headTable() {
    return parseMachine(R"({"name": "ht", "axes": [{"letter": "C", "on": "table", "direction": [0, 0, 1]},
                            {"letter": "B", "on": "head", "direction": [0, 1, 0], "pivot": [0, 0, 150]}]})",
                        "ht.json");
}

/// An APT move between a drawn move's joints whose axis turns on a great circle between two
/// random axes.
Move randomAptMove(std::mt19937& rng, const AcMove& drawn) {
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    Move apt;
    apt.start = drawn.j0, apt.end = drawn.j1;
    apt.startAxis = glm::normalize(Vec3(uni(rng), uni(rng), uni(rng)));
    apt.axis = glm::normalize(*apt.startAxis + 1.5 * Vec3(uni(rng), uni(rng), uni(rng)));
    return apt;
}

}  // namespace

TEST_CASE("machine: xyzac-trt and xyzbc-trt match LinuxCNC's trt kinematics", "[machine]") {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    const Machine ac = loadMachine("xyzac-trt"), bc = loadMachine("xyzbc-trt");
    for (int i = 0; i < 200; ++i) {
        const Vec3 j(100 * uni(rng), 100 * uni(rng), 100 * uni(rng));
        const double tilt = 100 * uni(rng), spin = 360 * uni(rng);
        RotaryAngles a;
        a['A'] = tilt, a['C'] = spin;
        CHECK(distance(ac.partFromJoints(j, a), xyzacForward(j, tilt, spin)) < 1e-12);
        // The tool axis is the image of machine +z: the issue's (sin C sin A, cos C sin A, cos A).
        CHECK(distance(ac.toolAxis(a), xyzacAxis(tilt, spin)) < 1e-14);
        CHECK(distance(ac.jointsFromPart(xyzacForward(j, tilt, spin), a), j) < 1e-11);
        RotaryAngles b;
        b['B'] = tilt, b['C'] = spin;
        CHECK(distance(bc.partFromJoints(j, b), xyzbcForward(j, tilt, spin)) < 1e-12);
        const Vec3 bAxis = xyzbcForward(j + Vec3(0, 0, 1), tilt, spin) - xyzbcForward(j, tilt, spin);
        CHECK(distance(bc.toolAxis(b), bAxis) < 1e-12);
        CHECK(distance(bc.jointsFromPart(bc.partFromJoints(j, b), b), j) < 1e-11);
    }
}

TEST_CASE("machine: the law of a move reproduces the kinematics at every u", "[machine]") {
    const Machine ac = loadMachine("xyzac-trt");
    RotaryAngles from, to;
    from['A'] = -10, from['C'] = 20, to['A'] = -50, to['C'] = 95;
    const Vec3 j0(3, -7, 12), j1(-9, 4, 5);
    for (const bool tcp : {false, true}) {
        Move m;
        m.start = tcp ? j0 : ac.partFromJoints(j0, from);
        m.end = tcp ? j1 : ac.partFromJoints(j1, to);
        m.rotary = std::make_shared<const RotaryMotion>(ac.motion(from, to, tcp, j0, j1));
        const MotionLaw law(m);
        for (int k = 0; k <= 10; ++k) {
            const double u = k / 10.0;
            const double a = -10 - 40 * u, c = 20 + 75 * u;
            const Vec3 j = j0 + u * (j1 - j0);
            const ToolPose p = law.pose(u);
            CHECK(distance(p.tip, tcp ? j : xyzacForward(j, a, c)) < 1e-12);
            RotaryAngles at;
            at['A'] = a, at['C'] = c;
            CHECK(distance(p.axis, ac.toolAxis(at)) < 1e-14);
            // The velocity of the tool point 7 mm up the axis, against a central difference.
            const double h = 1e-6;
            auto point = [&](double v) {
                const ToolPose q = law.pose(v);
                return q.tip + 7.0 * q.axis;
            };
            if (k > 0 && k < 10) {
                const Vec3 fd = (point(u + h) - point(u - h)) / (2 * h);
                CHECK(distance(law.velocity(u, point(u)), fd) < 1e-6 * (1 + glm::length(fd)));
                CHECK(distance(law.twist(law.phase(u)).at(point(u)), fd) < 1e-6 * (1 + glm::length(fd)));
                CHECK(glm::length(fd) <= law.speedBound(7.0));
                // The velocity field is affine: the twist gives every point's, off the axis too.
                const Twist twist = law.twist(law.phase(u));
                for (const Vec3& y : {Vec3(40, -3, 8), Vec3(-5, 60, -20), p.tip})
                    CHECK(distance(twist.at(y), law.velocity(u, y)) < 1e-12 * (1 + glm::length(law.velocity(u, y))));
            }
        }
    }
}

TEST_CASE("machine: the law of random xyzac-trt moves matches the trt formulas at every u", "[machine]") {
    // The poses every turning sweep of a machine's move starts from: the tip is the joints' line
    // under TCP and its image under the forward kinematics otherwise, the axis the issue's formula,
    // the angles linear in u.
    const Machine ac = loadMachine("xyzac-trt");
    std::mt19937 rng(20261130);
    for (int i = 0; i < 60; ++i) {
        const AcMove drawn = randomAcMove(rng);
        const bool tcp = i % 2 == 0;
        const MotionLaw law(drawn.move(ac, tcp));
        for (int k = 0; k <= 16; ++k) {
            const double u = k / 16.0;
            const double a = drawn.from['A'] + u * (drawn.to['A'] - drawn.from['A']);
            const double c = drawn.from['C'] + u * (drawn.to['C'] - drawn.from['C']);
            const Vec3 j = drawn.j0 + u * (drawn.j1 - drawn.j0);
            const ToolPose p = law.pose(u);
            INFO("move " << i << (tcp ? " (TCP)" : " (identity)") << ", u = " << u);
            CHECK(distance(p.tip, tcp ? j : xyzacForward(j, a, c)) < 1e-11);
            CHECK(distance(p.axis, drawn.axis(u)) < 1e-14);
        }
    }
}

TEST_CASE("motion: a stretch of a move, as a move of its own, has the move's poses", "[machine]") {
    // Against the trt formulas (xyzac-trt, TCP and identity), the machine's own kinematics (a
    // head B turning in identity kinematics under a table C) and a great circle written out here
    // (APT), at s in [0, 1] of stretches [u0, u1] drawn down to a millionth of the move.
    const Machine ac = loadMachine("xyzac-trt");
    const Machine ht = headTable();
    std::mt19937 rng(20261201);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < 80; ++i) {
        const AcMove drawn = randomAcMove(rng);
        double u0 = unit(rng), u1 = unit(rng);
        if (u0 > u1) std::swap(u0, u1);
        if (i % 4 == 0) u1 = std::min(1.0, u0 + 1e-6);
        if (i % 8 == 1) u0 = 0.0, u1 = 1.0;
        INFO("move " << i << ", stretch [" << u0 << ", " << u1 << "]");
        const auto at = [&](double s) { return u0 + (u1 - u0) * s; };
        // xyzac-trt, under TCP and in identity kinematics.
        for (const bool tcp : {true, false}) {
            const MotionLaw law(subMove(drawn.move(ac, tcp), u0, u1));
            for (int k = 0; k <= 8; ++k) {
                const double u = at(k / 8.0);
                const Vec3 j = drawn.j0 + u * (drawn.j1 - drawn.j0);
                const double a = drawn.from['A'] + u * (drawn.to['A'] - drawn.from['A']);
                const double c = drawn.from['C'] + u * (drawn.to['C'] - drawn.from['C']);
                const ToolPose p = law.pose(k / 8.0);
                CHECK(distance(p.tip, tcp ? j : xyzacForward(j, a, c)) < 1e-11);
                CHECK(distance(p.axis, drawn.axis(u)) < 1e-14);
            }
        }
        // A head turning in identity kinematics under a table: the machine's kinematics at u.
        RotaryAngles from, to;
        from['C'] = drawn.from['C'], to['C'] = drawn.to['C'];
        from['B'] = drawn.from['A'] / 2, to['B'] = drawn.to['A'] / 2;
        Move headMove;
        headMove.start = ht.partFromJoints(drawn.j0, from), headMove.end = ht.partFromJoints(drawn.j1, to);
        headMove.rotary = std::make_shared<const RotaryMotion>(ht.motion(from, to, false, drawn.j0, drawn.j1));
        const Move headPiece = subMove(headMove, u0, u1);
        const MotionLaw headLaw(headPiece);
        for (int k = 0; k <= 8; ++k) {
            const double u = at(k / 8.0);
            RotaryAngles angles;
            angles['B'] = from['B'] + u * (to['B'] - from['B']), angles['C'] = from['C'] + u * (to['C'] - from['C']);
            const ToolPose p = headLaw.pose(k / 8.0);
            CHECK(distance(p.tip, ht.partFromJoints(drawn.j0 + u * (drawn.j1 - drawn.j0), angles)) < 1e-10);
            CHECK(distance(p.axis, ht.toolAxis(angles)) < 1e-14);
        }
        CHECK(distance(headPiece.start, headLaw.pose(0.0).tip) < 1e-12);
        CHECK(distance(headPiece.end, headLaw.pose(1.0).tip) < 1e-12);
        // APT: the tip on the segment, the axis on the great circle a0 cos(t) + b sin(t).
        const Move apt = randomAptMove(rng, drawn);
        const MotionLaw aptLaw(subMove(apt, u0, u1));
        const Vec3 a0 = *apt.startAxis;
        const double theta = std::acos(std::clamp(glm::dot(a0, apt.axis), -1.0, 1.0));
        const Vec3 b = glm::normalize(apt.axis - glm::dot(apt.axis, a0) * a0);
        for (int k = 0; k <= 8; ++k) {
            const double u = at(k / 8.0);
            const ToolPose p = aptLaw.pose(k / 8.0);
            CHECK(distance(p.tip, apt.start + u * (apt.end - apt.start)) < 1e-12);
            CHECK(distance(p.axis, std::cos(theta * u) * a0 + std::sin(theta * u) * b) < 1e-13);
        }
    }
    // A fixed axis: the segment alone.
    Move still;
    still.start = Vec3(1, 2, 3), still.end = Vec3(11, -8, 3), still.axis = glm::normalize(Vec3(0, 1, 1));
    const Move piece = subMove(still, 0.25, 0.5);
    CHECK(distance(piece.start, Vec3(3.5, -0.5, 3)) < 1e-15);
    CHECK(distance(piece.end, Vec3(6, -3, 3)) < 1e-15);
    CHECK(!piece.turns());
    CHECK(piece.axis == still.axis);
}

TEST_CASE("machine: the acceleration bound of a tool point on the axis holds with TCP, in APT and in identity",
          "[machine]") {
    // A second central difference of the pose (h = 1e-3: its rounding error, about 1e-16 x 100 mm
    // / h^2, is 1e-8 mm) never exceeds the bound; for a great circle the bound is the exact
    // |y''| = r theta^2, and a sinusoid's second difference falls just short of it.
    constexpr double kH = 1e-3, kRounding = 1e-6;
    const Machine ac = loadMachine("xyzac-trt");
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    for (int i = 0; i < 40; ++i) {
        const AcMove drawn = randomAcMove(rng);
        const double r = 1 + 20 * (uni(rng) + 1);
        // The same move's axis point from the issue's formula.
        const auto point = [&](double u) { return drawn.j0 + u * (drawn.j1 - drawn.j0) + r * drawn.axis(u); };
        const double bound = MotionLaw(drawn.move(ac, true)).axisPointAccelerationBound(r);
        const Move apt = randomAptMove(rng, drawn);
        const MotionLaw slerp(apt);
        const double theta = std::acos(std::clamp(glm::dot(*apt.startAxis, apt.axis), -1.0, 1.0));
        CHECK(slerp.axisPointAccelerationBound(r) == Approx(r * theta * theta).epsilon(1e-12));
        auto aptPoint = [&](double u) {
            const ToolPose q = slerp.pose(u);
            return q.tip + r * q.axis;
        };
        for (int k = 1; k < 20; ++k) {
            const double u = k / 20.0;
            const Vec3 d2 = (point(u + kH) - 2.0 * point(u) + point(u - kH)) / (kH * kH);
            CHECK(glm::length(d2) <= bound + kRounding);
            const Vec3 e2 = (aptPoint(u + kH) - 2.0 * aptPoint(u) + aptPoint(u - kH)) / (kH * kH);
            CHECK(glm::length(e2) <= r * theta * theta + kRounding);
        }
        // In identity kinematics the tables carry the joints' straight line: the axis point r up
        // machine z, from LinuxCNC's formulas.
        const double carriedBound = MotionLaw(drawn.move(ac, false)).axisPointAccelerationBound(r);
        const auto carried = [&](double u) {
            const double a = drawn.from['A'] + u * (drawn.to['A'] - drawn.from['A']);
            const double c = drawn.from['C'] + u * (drawn.to['C'] - drawn.from['C']);
            return xyzacForward(drawn.j0 + u * (drawn.j1 - drawn.j0) + Vec3(0, 0, r), a, c);
        };
        double largest = 0.0;
        for (int k = 1; k < 40; ++k) {
            const double u = k / 40.0;
            const Vec3 d2 = (carried(u + kH) - 2.0 * carried(u) + carried(u - kH)) / (kH * kH);
            CHECK(glm::length(d2) <= carriedBound + kRounding);
            largest = std::max(largest, glm::length(d2));
        }
        // It grows with the height up the axis at |a''|'s bound, as the sweep takes it
        // (TurningSweep's pivot bend plus axisBendBound times the height).
        for (const MotionLaw& law : {MotionLaw(drawn.move(ac, false)), MotionLaw(drawn.move(ac, true)), slerp})
            CHECK(law.axisPointAccelerationBound(r) ==
                  Approx(law.axisPointAccelerationBound(0.0) + law.axisBendBound() * r).epsilon(1e-12));
        // Not so loose that linear nodes would gain nothing: it takes each term at its largest over
        // the move, which these moves' differences reach to within a factor of 8 or less.
        CHECK(carriedBound <= 10.0 * largest);
    }
}

TEST_CASE("machine: the axis's third-derivative bound holds with TCP and in APT, not in identity", "[machine]") {
    // A central third difference of the unit axis, (a(u + 2h) - 2 a(u + h) + 2 a(u - h) - a(u - 2h))
    // / 2h^3 with h = 1e-2: its truncation error is h^2 |a^(5)| / 4 <= 2.5e-5 w^5 and its rounding
    // error about 1e-16 / h^3 = 1e-10. For a great circle |a'''| = theta^3 exactly.
    constexpr double kH = 1e-2;
    const auto third = [&](auto&& axis, double u) {
        return (axis(u + 2 * kH) - 2.0 * axis(u + kH) + 2.0 * axis(u - kH) - axis(u - 2 * kH)) / (2 * kH * kH * kH);
    };
    const Machine ac = loadMachine("xyzac-trt");
    std::mt19937 rng(12);
    for (int i = 0; i < 40; ++i) {
        const AcMove drawn = randomAcMove(rng);
        const auto axis = [&](double u) { return drawn.axis(u); };
        const double rate =
            (std::abs(drawn.to['A'] - drawn.from['A']) + std::abs(drawn.to['C'] - drawn.from['C'])) * kDeg;
        const double bound = MotionLaw(drawn.move(ac, true)).axisJerkBound();
        CHECK(bound == Approx(rate * rate * rate).epsilon(1e-12));
        const Move apt = randomAptMove(rng, drawn);
        const MotionLaw slerp(apt);
        const double theta = std::acos(std::clamp(glm::dot(*apt.startAxis, apt.axis), -1.0, 1.0));
        CHECK(slerp.axisJerkBound() == Approx(theta * theta * theta).epsilon(1e-12));
        const auto aptAxis = [&](double u) { return slerp.pose(u).axis; };
        double largest = 0.0;
        for (int k = 1; k < 20; ++k) {
            const double u = k / 20.0;
            const double d3 = glm::length(third(axis, u));
            CHECK(d3 <= bound + 2.5e-5 * std::pow(rate, 5) + 1e-8);
            largest = std::max(largest, d3);
            CHECK(glm::length(third(aptAxis, u)) == Approx(theta * theta * theta).margin(2.5e-5 * std::pow(theta, 5) + 1e-8));
        }
        // The bound is no more than the turns' rates allow: some pose comes within a factor 8.
        CHECK(largest >= bound / 8.0);
        CHECK(std::isinf(MotionLaw(drawn.move(ac, false)).axisJerkBound()));
    }
}

TEST_CASE("machine: the axis turn bound holds and is tight, and sees a table spin under an upright tool",
          "[machine]") {
    // With A and C linear in u, the issue's axis (sin C sin A, cos C sin A, cos A) turns at
    // |a'|^2 = A'^2 + sin^2 A C'^2 exactly. The bound must hold at every u (checked on a grid of
    // spacing 1 / 4000) and exceed the largest rate by no more than its sampling slack,
    // rates max(rates, 1) / 64 with rates = |A'| + |C'| (motion.cpp), plus what the grid may miss
    // of the largest rate: every u lies within 1 / 8000 of a grid point, and |a''| <= rates^2.
    const Machine ac = loadMachine("xyzac-trt");
    std::mt19937 rng(29);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    for (int i = 0; i < 60; ++i) {
        RotaryAngles from, to;
        // A third of the moves stay within 3 degrees of upright while C turns up to 90 degrees.
        // A quarter turn C by at most 1.8 degrees (and A, unless upright, 0.8), as real programs' moves
        // do: the bound then takes fewer samples.
        const bool upright = i % 3 == 0;
        const double scale = i % 4 == 3 ? 0.02 : 1.0;
        from['A'] = upright ? 3 * uni(rng) : 80 * uni(rng), from['C'] = 180 * uni(rng);
        to['A'] = upright ? 3 * uni(rng) : from['A'] + scale * 40 * uni(rng);
        to['C'] = from['C'] + scale * 90 * uni(rng);
        const double rateA = (to['A'] - from['A']) * kDeg, rateC = (to['C'] - from['C']) * kDeg;
        const Vec3 j0(30 * uni(rng), 30 * uni(rng), 30 * uni(rng)), j1(30 * uni(rng), 30 * uni(rng), 30 * uni(rng));
        for (const bool tcp : {true, false}) {
            Move m;
            m.start = j0, m.end = j1;
            m.rotary = std::make_shared<const RotaryMotion>(ac.motion(from, to, tcp, j0, j1));
            const MotionLaw law(m);
            const double bound = law.axisTurnBound();
            double largest = 0.0;
            for (int k = 0; k <= 4000; ++k) {
                const double a = (from['A'] + k / 4000.0 * (to['A'] - from['A'])) * kDeg;
                largest = std::max(largest, std::hypot(rateA, std::sin(a) * rateC));
            }
            const double rates = std::abs(rateA) + std::abs(rateC);
            INFO("move " << i << (tcp ? " TCP" : " identity") << ": bound " << bound << ", largest rate " << largest);
            CHECK(bound >= largest);
            // The sampling's slack, at most rates max(rates, 1) / 64; the oracle's own, rates^2 / 8000.
            CHECK(bound <= largest + rates * std::max(rates, 1.0) / 64.0 + rates * rates / 8000.0 + 1e-12);
            CHECK(bound <= rates);
            // Upright, C's turn barely counts: sin A <= sin 3 degrees.
            if (upright)
                CHECK(bound <= std::abs(rateA) + 0.053 * std::abs(rateC) + rates * std::max(rates, 1.0) / 64.0);
        }
    }
    // On a great circle the axis turns at its angle, uniformly.
    Move apt;
    apt.startAxis = glm::normalize(Vec3(0.2, -0.4, 1.0));
    apt.axis = glm::normalize(Vec3(-0.5, 0.3, 0.8));
    const double theta = std::acos(glm::dot(*apt.startAxis, apt.axis));
    CHECK(MotionLaw(apt).axisTurnBound() == Approx(theta).epsilon(1e-12));
    // A table spinning under an upright tool turns no axis: the bound is its sampling slack alone,
    // a fortieth of the table's rate.
    RotaryAngles from, to;
    from['A'] = to['A'] = 0, from['C'] = 10, to['C'] = 100;
    Move spin;
    spin.rotary = std::make_shared<const RotaryMotion>(ac.motion(from, to, true, Vec3(5, 0, 0), Vec3(5, 0, 0)));
    const double rate = 90 * kDeg;
    CHECK(MotionLaw(spin).axisTurnBound() <= rate * rate / 64.0 + 1e-12);
}

TEST_CASE("machine: a head that turns in identity kinematics swings the tool about its travelling pivot",
          "[machine]") {
    // A table C about z and a head B about y pivoting 150 above the tip: a tool point v (relative
    // to the tip at B = 0) of joints j sits at Rz(-C) (j + P + Ry(B) (v - P)), P = (0, 0, 150).
    const Machine m = headTable();
    auto forward = [](const Vec3& j, const Vec3& v, double bDeg, double cDeg) {
        const double b = bDeg * kDeg, c = -cDeg * kDeg;
        const Vec3 w = v - Vec3(0, 0, 150);
        const Vec3 x = j + Vec3(0, 0, 150) + Vec3(std::cos(b) * w.x + std::sin(b) * w.z, w.y, -std::sin(b) * w.x + std::cos(b) * w.z);
        return Vec3(std::cos(c) * x.x - std::sin(c) * x.y, std::sin(c) * x.x + std::cos(c) * x.y, x.z);
    };
    // The table turning too, and the head alone.
    for (const double c1 : {80.0, 10.0}) {
        INFO("C from 10 to " << c1);
        RotaryAngles from, to;
        from['B'] = -20, from['C'] = 10, to['B'] = 35, to['C'] = c1;
        const Vec3 j0(3, -7, 12), j1(-9, 4, 5);
        CHECK_FALSE(m.headsStill(from, to));
        Move mv;
        mv.start = m.partFromJoints(j0, from);
        mv.end = m.partFromJoints(j1, to);
        mv.rotary = std::make_shared<const RotaryMotion>(m.motion(from, to, false, j0, j1));
        REQUIRE(mv.rotary->tipCarried);
        REQUIRE(mv.rotary->headTurns.size() == 1);
        const MotionLaw law(mv);
        for (int k = 0; k <= 10; ++k) {
            const double u = k / 10.0;
            const double b = -20 + 55 * u, c = 10 + (c1 - 10) * u;
            const Vec3 j = j0 + u * (j1 - j0);
            const ToolPose p = law.pose(u);
            CHECK(distance(p.tip, forward(j, Vec3(0.0), b, c)) < 1e-11);
            CHECK(distance(p.axis, forward(j, Vec3(0, 0, 1), b, c) - forward(j, Vec3(0.0), b, c)) < 1e-12);
            if (k == 0) CHECK(distance(p.tip, mv.start) < 1e-11);
            if (k == 10) CHECK(distance(p.tip, mv.end) < 1e-11);
            // Tool points up the axis and off it: their velocity against a central difference of
            // the formula, and the speed bound.
            if (k == 0 || k == 10) continue;
            for (const Vec3& v : {Vec3(0, 0, 7), Vec3(3, 0, 0), Vec3(0, -3, 20)}) {
                const double h = 1e-6;
                auto at = [&](double w) { return forward(j0 + w * (j1 - j0), v, -20 + 55 * w, 10 + (c1 - 10) * w); };
                const Vec3 fd = (at(u + h) - at(u - h)) / (2 * h);
                INFO("u " << u << ", v (" << v.x << ", " << v.y << ", " << v.z << ")");
                CHECK(distance(law.velocity(u, at(u)), fd) < 1e-6 * (1 + glm::length(fd)));
                CHECK(distance(law.twist(law.phase(u)).at(at(u)), fd) < 1e-6 * (1 + glm::length(fd)));
                CHECK(glm::length(fd) <= law.speedBound(glm::length(v)));
            }
        }
    }
    // The G-code reader makes such moves in M429 (the machine starts in identity kinematics).
    GcodeOptions o;
    o.machine = m;
    const Program p = parseGcode("G0 X0 Y0 Z0 B0 C0\nG1 X10 B30 F100\n", "h.ngc", o);
    REQUIRE(p.path.moves.size() == 1);
    const Move& g = p.path.moves[0];
    REQUIRE(g.rotary);
    CHECK(g.rotary->headTurns.size() == 1);
    CHECK(distance(g.end, forward(Vec3(10, 0, 0), Vec3(0.0), 30, 0)) < 1e-11);
}

TEST_CASE("machine: the acceleration bound holds where heads turn in identity kinematics", "[machine]") {
    // Second central differences (h = 1e-3, as above) of tool points on and off the axis, from
    // formulas written out here, never exceed the bound, which comes within a factor of 12 of
    // them (10.5 at worst here: it takes each lever at its longest, the head's pivot's included,
    // at every turn). Two machines: a table C under a head B pivoting 150 above the tip, whose tool point v
    // of joints j sits at Rz(-C) (j + P + Ry(B) (v - P)), P = (0, 0, 150); and a head C about z
    // pivoting 200 above the tip, carrying a head B about y pivoting 150 above it, at
    // j + Q + Rz(C) (P + Ry(B) (v - P) - Q), Q = (0, 0, 200).
    constexpr double kH = 1e-3, kRounding = 1e-6;
    const Machine ht = headTable();
    const Machine hh = parseMachine(
        R"({"name": "hh", "axes": [{"letter": "C", "on": "head", "direction": [0, 0, 1], "pivot": [0, 0, 200]},
            {"letter": "B", "on": "head", "direction": [0, 1, 0], "pivot": [0, 0, 150]}]})",
        "hh.json");
    const auto ry = [](double deg, const Vec3& w) {
        const double b = deg * kDeg;
        return Vec3(std::cos(b) * w.x + std::sin(b) * w.z, w.y, -std::sin(b) * w.x + std::cos(b) * w.z);
    };
    const auto rz = [](double deg, const Vec3& w) {
        const double c = deg * kDeg;
        return Vec3(std::cos(c) * w.x - std::sin(c) * w.y, std::sin(c) * w.x + std::cos(c) * w.y, w.z);
    };
    const Vec3 P(0, 0, 150), Q(0, 0, 200);
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    for (int i = 0; i < 40; ++i) {
        const bool tableAndHead = i % 2 == 0;
        RotaryAngles from, to;
        from['B'] = 60 * uni(rng), from['C'] = 180 * uni(rng);
        to['B'] = from['B'] + 40 * uni(rng), to['C'] = from['C'] + (i % 4 < 2 ? 120 : 5) * uni(rng);
        const Vec3 j0(50 * uni(rng), 50 * uni(rng), 50 * uni(rng)), j1(50 * uni(rng), 50 * uni(rng), 50 * uni(rng));
        const Vec3 v(3 * uni(rng), 3 * uni(rng), 30 * (uni(rng) + 1));
        const auto point = [&](double u, const Vec3& w) {
            const double b = from['B'] + u * (to['B'] - from['B']), c = from['C'] + u * (to['C'] - from['C']);
            const Vec3 j = j0 + u * (j1 - j0);
            return tableAndHead ? rz(-c, j + P + ry(b, w - P)) : j + Q + rz(c, P + ry(b, w - P) - Q);
        };
        Move mv;
        const Machine& m = tableAndHead ? ht : hh;
        mv.start = m.partFromJoints(j0, from), mv.end = m.partFromJoints(j1, to);
        mv.rotary = std::make_shared<const RotaryMotion>(m.motion(from, to, false, j0, j1));
        REQUIRE(mv.rotary->tipCarried);
        REQUIRE_FALSE(mv.rotary->headTurns.empty());
        const MotionLaw law(mv);
        const double bound = law.axisPointAccelerationBound(glm::length(v));
        INFO("move " << i << (tableAndHead ? " (table and head)" : " (two heads)") << ", bound " << bound);
        double largest = 0.0;
        for (int k = 1; k < 40; ++k) {
            const double u = k / 40.0;
            // The formulas are the law's: its tip and axis.
            const ToolPose p = law.pose(u);
            CHECK(distance(p.tip, point(u, Vec3(0.0))) < 1e-10);
            CHECK(distance(p.axis, point(u, Vec3(0, 0, 1)) - point(u, Vec3(0.0))) < 1e-12);
            const Vec3 d2 = (point(u + kH, v) - 2.0 * point(u, v) + point(u - kH, v)) / (kH * kH);
            CHECK(glm::length(d2) <= bound + kRounding);
            largest = std::max(largest, glm::length(d2));
        }
        CHECK(bound <= 12.0 * largest);
        // It grows with the reach at |a''|'s bound, as the sweep takes it (note j).
        CHECK(law.axisPointAccelerationBound(7.0) ==
              Approx(law.axisPointAccelerationBound(0.0) + law.axisBendBound() * 7.0).epsilon(1e-12));
    }
}

TEST_CASE("motion: poses stepped by the angle sum stay within kPhaseStepError of the exact ones", "[machine]") {
    // Random bisection paths to the search's deepest level (60): each middle phase is stepped
    // from its node's start, as TurningSweep does, and its pose is compared with the pose made
    // from the middle's own sines and cosines. Bound: m steps, n turns, a point at distance d
    // from the pivots moves by at most m n d kPhaseStepError (motion.h).
    const Machine ac = loadMachine("xyzac-trt");
    const Machine ht = headTable();
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    for (int i = 0; i < 60; ++i) {
        RotaryAngles from, to;
        const Vec3 j0(80 * uni(rng), 80 * uni(rng), 80 * uni(rng)), j1(80 * uni(rng), 80 * uni(rng), 80 * uni(rng));
        Move m;
        m.start = j0, m.end = j1;
        std::size_t turns = 1;
        double d = 1.0 + std::max(glm::length(j0), glm::length(j1));
        if (i % 3 == 0) {  // APT: one great circle
            m.startAxis = glm::normalize(Vec3(uni(rng), uni(rng), uni(rng)));
            m.axis = glm::normalize(*m.startAxis + 1.5 * Vec3(uni(rng), uni(rng), uni(rng)));
        } else if (i % 3 == 1) {  // xyzac, TCP or identity
            from['A'] = 90 * uni(rng), from['C'] = 360 * uni(rng);
            to['A'] = 90 * uni(rng), to['C'] = 360 * uni(rng);
            m.rotary = std::make_shared<const RotaryMotion>(ac.motion(from, to, i % 2 == 0, j0, j1));
            turns = 2;
            d += 30.0;  // the pivots' offsets
        } else {  // a turning head and table in identity kinematics
            from['B'] = 60 * uni(rng), from['C'] = 360 * uni(rng);
            to['B'] = 60 * uni(rng), to['C'] = 360 * uni(rng);
            m.rotary = std::make_shared<const RotaryMotion>(ht.motion(from, to, false, j0, j1));
            REQUIRE(m.rotary->headTurns.size() == 1);
            turns = 2;
            d += 300.0;
        }
        const MotionLaw law(m);
        TurnPhase start = law.phase(0.0);
        for (int level = 0; level < 60; ++level) {
            const TurnPhase mid = law.advance(start, law.step(std::ldexp(1.0, -(level + 1))));
            const ToolPose stepped = law.pose(mid), exact = law.pose(mid.u);
            const double bound = double(level + 1) * double(turns) * kPhaseStepError;
            INFO("case " << i << ", level " << level);
            CHECK(distance(stepped.axis, exact.axis) <= bound + 4.0 * std::numeric_limits<double>::epsilon());
            CHECK(distance(stepped.tip, exact.tip) <= bound * d);
            if (rng() % 2) start = mid;
        }
    }
}

TEST_CASE("motion: a law refuses more turns than A, B and C make", "[machine]") {
    Move m;
    RotaryMotion r;
    r.turns.assign(kMaxTurns + 1, RotaryTurn{Vec3(0, 0, 1), Vec3(0.0), 0.0, 0.5});
    m.rotary = std::make_shared<const RotaryMotion>(r);
    CHECK_THROWS_WITH(MotionLaw(m), Contains("at most 3"));
    r.turns.pop_back();
    m.rotary = std::make_shared<const RotaryMotion>(r);
    CHECK_NOTHROW(MotionLaw(m));
}

TEST_CASE("motion: a law refuses opposite axes, and turns on axes short of opposite", "[machine]") {
    // Within kParallel of opposite no one great circle joins the axes: refused. A turn of 1e-7 rad short of opposite is a half turn like any other.
    const Vec3 axis = glm::normalize(Vec3(0.3, -0.4, 0.8));
    const Vec3 across = glm::normalize(glm::cross(axis, Vec3(1, 0, 0)));
    Move m;
    m.start = Vec3(1, 2, 3), m.end = Vec3(4, 5, 6), m.axis = axis;
    for (const double shortOf : {0.0, 1e-13, 1e-7}) {
        INFO("the start axis " << shortOf << " rad short of opposite");
        m.startAxis = glm::normalize(-std::cos(shortOf) * axis + std::sin(shortOf) * across);
        if (shortOf < tol::kParallel) {
            CHECK_THROWS_WITH(MotionLaw(m), Contains("opposite"));
            continue;
        }
        const MotionLaw law(m);
        // The turn's axis a0 x a1 is known to about machine epsilon over its length, sin(shortOf):
        // the end pose's axis strays by as much.
        CHECK(distance(law.pose(1.0).axis, axis) < 1e-15 / shortOf);
        CHECK(distance(law.pose(0.0).axis, *m.startAxis) < 1e-15);
        // Half way, the axis stands a quarter turn from both ends.
        const Vec3 half = law.pose(0.5).axis;
        CHECK(std::abs(glm::dot(half, axis)) < 1e-7);
        CHECK(std::abs(glm::dot(half, *m.startAxis)) < 1e-7);
    }
}

TEST_CASE("machine: description files and their errors", "[machine]") {
    const Machine m = parseMachine(
        R"({"name": "ht", "tcp_at_start": true, "axes": [{"letter": "C", "on": "table", "direction": [0, 0, 2]},
            {"letter": "B", "on": "head", "direction": [0, 1, 0], "pivot": [0, 0, 150]}]})",
        "ht.json");
    CHECK(m.name == "ht");
    CHECK(m.tcpAtStart);
    REQUIRE(m.axes.size() == 2);
    CHECK(m.axes[0].direction == Vec3(0, 0, 1));
    RotaryAngles a;
    a['B'] = 90;
    // A head B of +90 degrees turns the tool's +z to +x; its pivot 150 above the tip swings the tip.
    CHECK(distance(m.toolAxis(a), Vec3(1, 0, 0)) < 1e-15);
    CHECK(distance(m.partFromJoints(Vec3(0.0), a), Vec3(-150, 0, 150)) < 1e-12);
    CHECK_FALSE(m.headsStill(RotaryAngles{}, a));
    CHECK_THROWS_WITH(parseMachine("{\n  \"axes\": [\n  {\"letter\": \"A\",, }]}", "bad.json"),
                      Contains("bad.json:3:") && Contains("not valid JSON"));
    CHECK_THROWS_WITH(parseMachine("{}", "x.json"), Contains("x.json") && Contains("\"axes\""));
    // A key given twice, which the JSON library resolves silently, and nesting so deep that the
    // library's recursion overflowed the stack: located errors (jsonTextFault).
    CHECK_THROWS_WITH(parseMachine("{\"axes\": [{\"letter\": \"A\",\n \"direction\": [1, 0, 0], \"direction\": [0, 1, 0]}]}",
                                   "dup.json"),
                      Contains("dup.json:2:26: error: machine description: the key \"direction\" is given twice"));
    CHECK_THROWS_WITH(parseMachine("{\"axes\": [{\"letter\": \"A\", \"direction\": [1, 0, 0], \"pivot\": " +
                                       std::string(60000, '[') + std::string(60000, ']') + "}]}",
                                   "deep.json"),
                      Contains("deep.json:1:") && Contains("nested deeper than 64 levels"));
    CHECK_THROWS_WITH(parseMachine(R"({"axes": [{"letter": "A", "direction": [1, 0, 0]}, {"letter": "A", "direction": [0, 1, 0]}]})", "d.json"),
                      Contains("twice"));
    CHECK_THROWS_WITH(parseMachine(R"({"axes": [{"letter": "D", "direction": [1, 0, 0]}]})", "d.json"), Contains("letter"));
    CHECK_THROWS_WITH(parseMachine(R"({"axes": [{"letter": "A", "direction": [0, 0, 0]}]})", "d.json"), Contains("zero"));
    CHECK_THROWS_WITH(loadMachine("no-such-machine"), Contains("xyzac-trt") && Contains("no-such-machine"));
    // Read through a job's file source where one is given, as its programs are: the disk is not
    // asked, and a name the source lacks is the same error.
    const auto source = [](const std::string& path) -> std::optional<std::string> {
        if (path != "in/ht.json") return std::nullopt;
        return R"({"name": "sourced", "axes": [{"letter": "B", "on": "head", "direction": [0, 1, 0]}]})";
    };
    CHECK(loadMachine("in/ht.json", source).name == "sourced");
    CHECK(loadMachine("xyzbc-trt", source).name == "xyzbc-trt");
    CHECK_THROWS_WITH(loadMachine("in/none.json", source), Contains("in/none.json") && Contains("no file to read"));
    CHECK_THROWS_WITH(loadMachine("in/ht.json", [](const std::string&) -> std::optional<std::string> {
                          return std::string("{\"axes\": 5}");
                      }),
                      Contains("in/ht.json:1:10: error"));
    // Wrong types, unknown keys and numbers beyond a double's range: each an error of this reader's
    // own, never the JSON library's, at the value or key at fault (columns counted by hand).
    const struct {
        const char* text;
        const char* message;
        const char* place;
    } bad[] = {
        {R"({"name": 5, "axes": [{"letter": "A", "direction": [1, 0, 0]}]})", "\"name\" must be a string",
         "m.json:1:10: error"},
        {R"({"axes": [{"letter": 5, "direction": [1, 0, 0]}]})", "\"letter\" must be a string", "m.json:1:22: error"},
        {R"({"axes": [{"letter": "A", "on": 5, "direction": [1, 0, 0]}]})", "axis A: \"on\" must be a string",
         "m.json:1:33: error"},
        {R"({"axes": [5]})", "each axis must be a JSON object", "m.json:1:11: error"},
        {R"({"axes": [{"letter": "A", "direction": [1, 0, 0], "pivto": [0, 0, 5]}]})", "axis A: unknown key \"pivto\"",
         "m.json:1:51: error"},
        {R"({"axis": [{"letter": "A", "direction": [1, 0, 0]}], "axes": [{"letter": "A", "direction": [1, 0, 0]}]})",
         "unknown key \"axis\"", "m.json:1:2: error"},
        {R"({"axes": [{"letter": "A", "direction": [1e999, 0, 0]}]})", "beyond the range of a double",
         "m.json:1:41: error"},
        {R"({"axes": [{"letter": "A", "direction": [1, 0, 0], "pivot": [1e300, 0, 0]}]})", "pivot lies beyond",
         "m.json:1:60: error"},
    };
    for (const auto& b : bad) {
        INFO(b.text);
        CHECK_THROWS_WITH(parseMachine(b.text, "m.json"), Contains(b.place) && Contains(b.message));
    }
    // A direction so long that its length overflows is still a direction.
    const Machine h = parseMachine(R"({"axes": [{"letter": "A", "direction": [1e300, 0, 0]},
                                                {"letter": "C", "direction": [0, -1e300, -1e300]}]})",
                                   "h.json");
    REQUIRE(h.axes.size() == 2);
    CHECK(h.axes[0].direction == Vec3(1, 0, 0));
    CHECK(distance(h.axes[1].direction, -Vec3(0, 1, 1) / std::sqrt(2.0)) < 1e-15);
}

TEST_CASE("machine: an error about what a value means names the value's line and column", "[machine]") {
    // Each file is written to disk and read as `--machine FILE` reads it; the place of the value (or
    // key) at fault is counted by hand on the lines as written.
    const std::filesystem::path folder = testing::scratchFolder("dexelmill_machine_", "places");
    const struct {
        std::vector<std::string> lines;
        int line;
        int column;
        const char* message;
    } cases[] = {
        // The direction's opening bracket: line 5, after five blanks and `"direction": `.
        {{"{", "  \"name\": \"m\",", "  \"axes\": [", "    {\"letter\": \"A\",", "     \"direction\": [0, 0, 0]}", "  ]",
          "}"},
         5, 19, "axis A's direction is zero"},
        {{"{\"axes\": [", "  {\"letter\": \"C\", \"on\": \"tabel\", \"direction\": [0, 0, 1]}", "]}"},
         2, 25, "axis C: \"on\" must be \"table\" or \"head\""},
        // A missing key: the brace of the object that lacks it.
        {{"{", "  \"axes\": [", "    {\"on\": \"head\", \"direction\": [1, 0, 0]}", "  ]", "}"},
         3, 5, "each axis needs \"letter\""},
        {{"{\"axes\": [{\"letter\": \"B\"}]}"}, 1, 11, "axis B needs a \"direction\""},
        {{"", "  {\"name\": \"n\"}"}, 2, 3, "needs \"axes\""},
        // An unknown key: the key, its quote. One that needs escaping in a JSON pointer.
        {{"{\"axes\": [{\"letter\": \"B\", \"direction\": [0, 1, 0],", "           \"pivto\": [0, 0, 5]}]}"},
         2, 12, "axis B: unknown key \"pivto\""},
        {{"{\"name\": \"n\",", "\t\"a/b~\": 1, \"axes\": [{\"letter\": \"A\", \"direction\": [1, 0, 0]}]}"},
         2, 2, "unknown key \"a/b~\""},
        {{"{\"axes\": [{\"letter\": \"A\", \"direction\": [1, 0, 0],", "  \"pivot\": [0, 2e9, 0]}]}"},
         2, 12, "axis A's pivot lies beyond the 1e9 mm"},
        {{"{\"axes\": [", "", "  {\"letter\": \"A\", \"direction\": [1, 0]}]}"}, 3, 32,
         "axis A's direction must be an array of three numbers"},
        {{"{\"tcp_at_start\": \"yes\", \"axes\": [{\"letter\": \"A\", \"direction\": [1, 0, 0]}]}"}, 1, 18,
         "\"tcp_at_start\" must be true or false"},
        {{"{\"axes\": [{\"letter\": \"A\", \"direction\": [1, 0, 0]},", "          {\"letter\": \"A\", \"direction\": [0, 1, 0]}]}"},
         2, 22, "rotary axis A is described twice"},
        {{"", "", "  [1]"}, 3, 3, "must be a JSON object"},
        {{"{\"axes\": {}}"}, 1, 10, "needs \"axes\""},
    };
    for (const bool crlf : {false, true}) {
        for (const auto& c : cases) {
            std::string text;
            for (const std::string& l : c.lines) text += l + (crlf ? "\r\n" : "\n");
            const std::string file = (folder / "m.json").string();
            std::ofstream(file, std::ios::binary) << text;
            INFO(text);
            try {
                loadMachine(file);
                FAIL("no error");
            } catch (const ParseError& e) {
                CHECK(e.where().line == c.line);
                CHECK(e.where().column == c.column);
                CHECK_THAT(e.message(), Contains(c.message));
                // Printed as every located input error is.
                CHECK_THAT(e.what(), Contains(file + ":" + std::to_string(c.line) + ":" + std::to_string(c.column) +
                                              ": error: "));
            }
        }
    }
}

TEST_CASE("G-code: rotary words need a machine, and M428 / M429 switch the kinematics", "[machine][gcode]") {
    GcodeOptions o;
    CHECK_THROWS_WITH(parseGcode("G0 X0 Y0 Z0 A0 C0\nG1 X1 C90\n", "r.ngc", o),
                      Contains("r.ngc:2:7") && Contains("--machine"));
    // A and C words that repeat the current angle need no machine.
    CHECK_NOTHROW(parseGcode("G0 X0 Y0 Z0 A0 C0\nG1 X1 A0\n", "r.ngc", o));

    o.machine = loadMachine("xyzac-trt");
    CHECK_THROWS_WITH(parseGcode("G0 X0 Y0 Z0\nG1 B10\n", "r.ngc", o), Contains("r.ngc:2:4") && Contains("no B axis"));
    {
        // A word that leaves the missing axis at zero is ignored, with a warning at the word,
        // counted once however often it comes.
        const Program p0 = parseGcode("G0 X0 Y0 Z0\nG1 X1 B0\nG1 X2 B0\n", "r.ngc", o);
        CHECK(p0.path.moves.size() == 2);
        int warned = 0;
        for (const Diagnostic& d : p0.diagnostics)
            if (d.message.find("no B axis: 'B0' leaves it at zero and is ignored (2 occurrences") != std::string::npos) {
                ++warned;
                CHECK(d.where.line == 2);
                CHECK(d.where.column == 7);
            }
        CHECK(warned == 1);
    }
    // An angle beyond 1e6 degrees, or a move turning more than ten turns, is refused where it is
    // written; ten turns in one move, and 1e6 degrees reached move by move, are not.
    CHECK_THROWS_WITH(parseGcode("G0 X0 Y0 Z0\nG1 X1 A[10**200]\n", "r.ngc", o),
                      Contains("r.ngc:2:7") && Contains("beyond the 1e6 degrees"));
    CHECK_THROWS_WITH(parseGcode("G0 X0 Y0 Z0\nG1 X1 C-1000001\n", "r.ngc", o), Contains("beyond the 1e6 degrees"));
    CHECK_THROWS_WITH(parseGcode("G0 X0 Y0 Z0 C10\nG1 X1 C3610.5\n", "r.ngc", o),
                      Contains("r.ngc:2:7") && Contains("turns 3600.5 degrees in one move"));
    CHECK_THROWS_WITH(parseGcode("G0 X0 Y0 Z0\nG91 G1 X1 C1800\nC-3601\n", "r.ngc", o),
                      Contains("r.ngc:3:1") && Contains("turns -3601 degrees"));
    CHECK_NOTHROW(parseGcode("G0 X0 Y0 Z0 C10\nG1 X1 C3610\n", "r.ngc", o));
    {
        std::string steps = "G0 X0 Y0 Z0\n";
        for (int k = 1; k <= 277; ++k) steps += "G1 C" + std::to_string(k * 3600) + "\n";
        CHECK_NOTHROW(parseGcode(steps + "G1 C1000000\n", "r.ngc", o));
    }
    CHECK_THROWS_WITH(parseGcode("G0 X0 Y0 Z0\nG2 X2 I1 C10\n", "r.ngc", o), Contains("r.ngc:2:") && Contains("G0/G1"));
    // Identity kinematics (the sim config's start): the joints are carried by the tables.
    const Program p = parseGcode("G0 X0 Y0 Z0 A0 C0\nG0 X10 C90\nG1 Z2\nM428\nG1 Z0\nG1 A-30 X12\nM429\nG1 Z5\n",
                                 "sw.ngc", o);
    const auto& mv = p.path.moves;
    REQUIRE(mv.size() == 5);
    CHECK(mv[0].turns());  // C turns: the tip runs on an arc about the C axis
    CHECK(distance(mv[0].end, xyzacForward(Vec3(10, 0, 0), 0, 90)) < 1e-12);
    CHECK_FALSE(mv[1].turns());
    CHECK(distance(mv[1].end, xyzacForward(Vec3(10, 0, 2), 0, 90)) < 1e-12);
    // Under TCP the position is the tip in the part frame: Z0 lowers it there.
    const Vec3 tip = xyzacForward(Vec3(10, 0, 2), 0, 90);
    CHECK(distance(mv[2].end, Vec3(tip.x, tip.y, 0)) < 1e-12);
    REQUIRE(mv[3].turns());
    CHECK(mv[3].rotary != nullptr);
    CHECK_FALSE(mv[3].rotary->tipCarried);
    CHECK(distance(mv[3].end, Vec3(12, tip.y, 0)) < 1e-12);
    CHECK(distance(mv[3].axis, Vec3(std::sin(90 * kDeg) * std::sin(-30 * kDeg), 0, std::cos(30 * kDeg))) < 1e-12);
    // Back to identity: the joints under that tip, then Z5 moves joint Z.
    RotaryAngles at;
    at['A'] = -30, at['C'] = 90;
    const Vec3 joints = o.machine->jointsFromPart(Vec3(12, tip.y, 0), at);
    CHECK(distance(mv[4].end, xyzacForward(Vec3(joints.x, joints.y, 5), -30, 90)) < 1e-9);
    CHECK(p.rotaryRanges[0].lo == -30);
    CHECK(p.rotaryRanges[2].hi == 90);

    // Work offsets of the rotary axes: G10 L2 sets G54's C offset to 30, so C0 turns the table to
    // 30; L20 makes the current 30 read as 5 (offset 25), so C10 goes to 35; G92 then makes 35
    // read as 0 (its own offset 10), so C5 goes to 40. A reset to zero offsets is no move at all.
    const Program w = parseGcode("G0 X0 Y0 Z0 A0 C0\nG10 L2 P1 X0 Y0 Z0 A0 C0\nG10 L2 P1 C30\nG1 X1 C0\n"
                                 "G10 L20 P1 C5\nG1 X2 C10\nG92 C0\nG1 X3 C5\n",
                                 "w.ngc", o);
    REQUIRE(w.path.moves.size() == 3);
    const double ends[3] = {30, 35, 40};
    for (int k = 0; k < 3; ++k) {
        INFO("move " << k);
        REQUIRE(w.path.moves[std::size_t(k)].rotary);
        RotaryAngles end;
        end['C'] = ends[k];
        CHECK(distance(w.path.moves[std::size_t(k)].axis, o.machine->toolAxis(end)) < 1e-15);
        CHECK(distance(w.path.moves[std::size_t(k)].end, xyzacForward(Vec3(k + 1.0, 0, 0), 0, ends[k])) < 1e-12);
    }
    CHECK(w.rotaryRanges[2].hi == 40);
    CHECK_THROWS_WITH(parseGcode("G0 X0 Y0 Z0\nG10 L2 P1 B5\n", "w.ngc", o), Contains("w.ngc:2:") && Contains("no B axis"));
}

TEST_CASE("G-code: a kinematics switch before X, Y and Z are known keeps the position unknown", "[machine][gcode]") {
    GcodeOptions o;
    o.machine = loadMachine("xyzac-trt");
    auto switchWarnings = [](const Program& p) {
        std::vector<Diagnostic> found;
        for (const Diagnostic& d : p.diagnostics)
            if (d.message.find("before X, Y and Z are all known") != std::string::npos) found.push_back(d);
        return found;
    };
    // Joint X10 at C90 with Y and Z never given: the tip's part position depends on them, so the
    // plunge after M428 (whose X is not programmed again) only places the tool.
    const Program guess = parseGcode("G21 G90\nM429\nG0 X10 C90\nM428\nG0 Y0 Z20\nG1 Z-8 F100\nM2\n", "g.ngc", o);
    CHECK(guess.path.moves.empty());
    const std::vector<Diagnostic> warned = switchWarnings(guess);
    REQUIRE(warned.size() == 1);
    CHECK(warned[0].where.line == 4);
    CHECK(warned[0].where.column == 1);
    CHECK(warned[0].message.find("M428") != std::string::npos);
    CHECK(warned[0].message.find("(Y, Z not yet programmed)") != std::string::npos);
    // Given X, Y and Z in the new frame, the tip goes where they say: straight down at the part's
    // (3, 4), as TCP positions are the tip in the part frame.
    const Program given =
        parseGcode("M429\nG0 X10 C90\nM428\nG0 X3 Y4 Z20\nG1 Z-8 F100\nM2\n", "g.ngc", o);
    REQUIRE(given.path.moves.size() == 1);
    CHECK(distance(given.path.moves[0].start, Vec3(3, 4, 20)) < 1e-12);
    CHECK(distance(given.path.moves[0].end, Vec3(3, 4, -8)) < 1e-12);
    // A switch before anything is known forgets nothing, and says nothing.
    CHECK(switchWarnings(parseGcode("M428\nG0 X0 Y0 Z20\nG1 Z-8 F100\n", "g.ngc", o)).empty());
}

TEST_CASE("G-code: extents, the cutting box and the feed length follow the tip's curve in identity kinematics",
          "[machine][gcode]") {
    GcodeOptions o;
    o.machine = loadMachine("xyzac-trt");
    // Joint X10 at z -8, then the table C turns under it: in the part frame the tip runs on the
    // circle of radius 10 about z at height -8 (C about z through the origin, A at zero).
    const auto run = [&](const std::string& c) {
        return parseGcode("G21 G90\nM429\nG0 X10 Y0 Z20 A0 C0\nG1 Z-8 F100\nG1 C" + c + "\nM2\n", "c.ngc", o);
    };
    const auto feed = [](const Program& p) {
        double sum = 0.0;
        for (const Move& m : p.path.moves) sum += tipLength(m);
        return sum;
    };
    const double r = 10.0, plunge = 28.0, pi = std::acos(-1.0);
    // Chords of a circle fall short of it by sag / (3 r) of its length: 2e-3 mm on ten turns.
    const double shortfall = 0.005;
    // The box holds the path and exceeds it by at most the polyline's sag.
    const auto holds = [](double got, double want, double outward) {
        CHECK(got * outward >= want * outward - 1e-9);
        CHECK(got * outward <= want * outward + kTipPathSag + 1e-9);
    };
    {
        // Ten full turns: the whole circle, 10 times its circumference.
        const Program p = run("3600");
        REQUIRE(p.path.moves.size() == 2);
        const Box b = p.path.bounds();
        holds(b.lo.x, -r, -1), holds(b.hi.x, r, 1), holds(b.lo.y, -r, -1), holds(b.hi.y, r, 1);
        holds(b.lo.z, -8, -1), holds(b.hi.z, 20, 1);
        CHECK(feed(p) == Approx(plunge + 10 * 2 * pi * r).margin(shortfall));
        // A flat D6 upright: the cuts' box is the circle's grown by its radius 3 across x and y.
        // The rim's pad for the axis's turn bound (the axis stands still here; the bound is
        // looser) keeps it within 0.05 mm.
        ToolTable tools;
        tools.emplace(1, flatEndMill(6.0));
        const Box cut = cuttingBounds(p.path, tools);
        for (int k = 0; k < 2; ++k) {
            CHECK(cut.lo[k] <= -(r + 3.0));
            CHECK(cut.lo[k] >= -(r + 3.0) - 0.05);
            CHECK(cut.hi[k] >= r + 3.0);
            CHECK(cut.hi[k] <= r + 3.0 + 0.05);
        }
    }
    {
        // A half turn: from (10, 0) through the quarter the table turns the tip into, to (-10, 0).
        const Program p = run("180");
        const Vec3 quarter = xyzacForward(Vec3(r, 0, -8), 0, 90);
        const Box b = p.path.bounds();
        holds(b.lo.x, -r, -1), holds(b.hi.x, r, 1);
        if (quarter.y < 0) holds(b.lo.y, -r, -1), holds(b.hi.y, 0, 1);
        else holds(b.lo.y, 0, -1), holds(b.hi.y, r, 1);
        CHECK(feed(p) == Approx(plunge + pi * r).margin(shortfall));
    }
    // A quarter turn: the quarter circle's 5 pi, not its chord's 10 sqrt(2).
    CHECK(feed(run("90")) == Approx(plunge + pi * r / 2).margin(shortfall));
}
