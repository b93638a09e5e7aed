// Moves of a machine's rotary axes (xyzac-trt, with TCP and in identity kinematics; a head B
// over a table C in identity kinematics) swept by TurningSweep, against a brute-force oracle that
// shares no code with it: the poses come from LinuxCNC's xyzac-trt forward kinematics written out
// here (y-offset 20, z-offset 10), or the head machine's written out here, the tools are analytic
// solids (a cylinder, a ball end), and the speed bounds are derived here for each machine alone.
//  Check 1: every output point is within epsilon of some pose: failing needs a certificate, a
//    branch and bound over u proving the point farther than epsilon + margin from every pose.
//  Check 2: every line point deeper than epsilon + margin inside a pose found by a dense search
//    over u (refined by golden sections) is in the output.
//  Normals: at each output end, the solver's normal lies within kNormalAngle + sqrt(2 epsilon / r)
//    of the tangent plane of the oracle's own boundary (where the dense search's depth changes
//    sign), found by finite differences (normal_stencil.h), as turning_normals_test.cpp argues.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include "dexelmill/machine/kinematics.h"
#include "dexelmill/sweep/turning.h"
#include "dexelmill/tool/builders.h"
#include "normal_stencil.h"
#include "support/trt_kinematics.h"

using namespace dexelmill;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kDy = 20.0, kDz = 10.0;  // the sim config's offsets
constexpr double kEpsilon = 1e-4;
constexpr double kMargin = 1e-6;

/// The head machine: a table C about z through the origin, and a head B about y whose pivot is
/// kPivot above the tip. A tool point v (relative to the tip at B = 0) of joints j sits at
/// Rz(-C) (j + P + Ry(B) (v - P)), P = (0, 0, kPivot).
constexpr double kPivot = 40.0;
const char* const kHeadMachine = R"({"name": "bc-head", "axes": [
    {"letter": "C", "on": "table", "direction": [0, 0, 1], "pivot": [0, 0, 0]},
    {"letter": "B", "on": "head", "direction": [0, 1, 0], "pivot": [0, 0, 40]}]})";

Vec3 rotY(const Vec3& v, double b) { return {std::cos(b) * v.x + std::sin(b) * v.z, v.y, -std::sin(b) * v.x + std::cos(b) * v.z}; }
Vec3 rotZ(const Vec3& v, double c) { return {std::cos(c) * v.x - std::sin(c) * v.y, std::sin(c) * v.x + std::cos(c) * v.y, v.z}; }

Vec3 headForward(const Vec3& j, const Vec3& v, double bDeg, double cDeg) {
    const Vec3 pivot(0, 0, kPivot);
    return rotZ(j + pivot + rotY(v - pivot, bDeg * kDeg), -cDeg * kDeg);
}

/// A flat end mill (ball = false) or ball end mill of radius r and length l, tip at the origin.
struct Solid {
    double r = 3, l = 20;
    bool ball = false;
    /// A signed clearance: positive outside, at most the distance outside; negative inside, its
    /// magnitude exactly the depth (the solid is an intersection of convex sets, whose clearances
    /// are exact, and the largest of them has both properties).
    double clearance(double z, double rho) const {
        if (!ball) return std::max({rho - r, -z, z - l});
        const double zc = std::clamp(z, r, l + r);  // capsule about the segment z in [r, l + r]
        return std::max(std::hypot(rho, z - zc) - r, z - l);
    }
};

struct Case {
    Vec3 j0, j1;   ///< joints (identity) or part-frame tips (TCP)
    double a0, a1, c0, c1;  ///< degrees (A, or B on the head machine)
    bool tcp = false;
    bool head = false;  ///< the head machine (identity kinematics), not xyzac-trt
};

class RotaryOracle {
  public:
    RotaryOracle(const Case& c, const Solid& s) : c_(c), s_(s) {
        const double reach = std::hypot(s.l, s.r);
        const double rateA = std::abs(c.a1 - c.a0) * kDeg, rateC = std::abs(c.c1 - c.c0) * kDeg;
        if (c.head) {
            // y = Rz(-C) (j + P + Ry(B) (v - P)): |y'| <= |j'| + |B'| |v - P| + |C'| |j + P + Ry(B) (v - P)|,
            // with |v - P| <= reach + |P| and |j| largest at an end of its segment.
            const double arm = reach + kPivot;
            speed_ = glm::length(c.j1 - c.j0) + rateA * arm +
                     rateC * (std::max(glm::length(c.j0), glm::length(c.j1)) + kPivot + arm);
        } else if (c.tcp) {
            // y = p + Q v: |y'| <= |p'| + (|A'| + |C'|) |y - p|.
            speed_ = glm::length(c.j1 - c.j0) + (rateA + rateC) * reach;
        } else {
            // y = Rz(-C) (D + Rx(-A) (x - D)), x a machine-frame tool point, D = (0, dy, dz):
            // |y'| <= |x'| + |A'| |x - D| + |C'| (|D| + |x - D|).
            const Vec3 d(0, kDy, kDz);
            const double far = std::max(glm::length(c.j0 - d), glm::length(c.j1 - d)) + reach;
            speed_ = glm::length(c.j1 - c.j0) + rateA * far + rateC * (glm::length(d) + far);
        }
    }

    void pose(double u, Vec3& tip, Vec3& axis) const {
        const double a = c_.a0 + u * (c_.a1 - c_.a0), c = c_.c0 + u * (c_.c1 - c_.c0);
        const Vec3 j = c_.j0 + u * (c_.j1 - c_.j0);
        if (c_.head) {
            tip = headForward(j, Vec3(0.0), a, c);
            axis = headForward(j, Vec3(0, 0, 1), a, c) - tip;
            return;
        }
        tip = c_.tcp ? j : testing::xyzacForward(j, a, c);
        axis = testing::xyzacAxis(a, c);
    }
    /// The line parameters within reach of the tip at some pose: the solid's whole extent along
    /// the line. Every tool point lies within hypot(l, r) of the tip, and between two of the
    /// kRangeGrid + 1 poses sampled the tip lies within speed_ / (2 kRangeGrid) of one of them.
    Interval lineRange(const Line& line) const {
        constexpr int kRangeGrid = 64;
        const double reach = std::hypot(s_.l, s_.r) + speed_ / (2.0 * kRangeGrid);
        Interval range = Interval::empty();
        for (int k = 0; k <= kRangeGrid; ++k) {
            Vec3 tip, axis;
            pose(double(k) / kRangeGrid, tip, axis);
            const double t = glm::dot(tip - line.origin, line.dir);
            range = range.hull({t - reach, t + reach});
        }
        return range;
    }
    double clearance(const Vec3& x, double u) const {
        Vec3 tip, axis;
        pose(u, tip, axis);
        const Vec3 d = x - tip;
        const double z = glm::dot(d, axis);
        return s_.clearance(z, glm::length(d - z * axis));
    }
    /// A certificate that x is farther than `margin` from every pose.
    bool certainlyOutside(const Vec3& x, double margin) const {
        struct Node {
            double ua, ub;
        };
        std::vector<Node> stack{{0.0, 1.0}};
        int nodes = 0;
        while (!stack.empty()) {
            const Node n = stack.back();
            stack.pop_back();
            const double um = 0.5 * (n.ua + n.ub), half = 0.5 * (n.ub - n.ua);
            const double c = clearance(x, um);
            if (c <= margin) return false;
            if (c - speed_ * half > margin) continue;
            if (++nodes > 200000) return false;
            stack.push_back({n.ua, um});
            stack.push_back({um, n.ub});
        }
        return true;
    }
    /// The greatest depth of x found over u (dense grid, then golden sections).
    double depth(const Vec3& x) const {
        constexpr int kGrid = 400;
        int best = 0;
        double bestC = 1e300;
        for (int k = 0; k <= kGrid; ++k) {
            const double c = clearance(x, double(k) / kGrid);
            if (c < bestC) bestC = c, best = k;
        }
        double lo = std::max(best - 1, 0) / double(kGrid), hi = std::min(best + 1, kGrid) / double(kGrid);
        for (int i = 0; i < 60; ++i) {
            const double m1 = lo + (hi - lo) * 0.382, m2 = lo + (hi - lo) * 0.618;
            if (clearance(x, m1) < clearance(x, m2)) hi = m2;
            else lo = m1;
        }
        return -std::min(bestC, clearance(x, 0.5 * (lo + hi)));
    }

  private:
    Case c_;
    Solid s_;
    double speed_ = 0;
};

/// The move the interpreter would make: poses at u = 0 and 1 and the machine's law.
Move machineMove(const Case& c) {
    const Machine m = c.head ? parseMachine(kHeadMachine, "bc-head.json") : loadMachine("xyzac-trt");
    const char tilt = c.head ? 'B' : 'A';
    RotaryAngles from, to;
    from[tilt] = c.a0, from['C'] = c.c0, to[tilt] = c.a1, to['C'] = c.c1;
    Move mv;
    mv.start = c.tcp ? c.j0 : m.partFromJoints(c.j0, from);
    mv.end = c.tcp ? c.j1 : m.partFromJoints(c.j1, to);
    mv.startAxis = m.toolAxis(from);
    mv.axis = m.toolAxis(to);
    mv.rotary = std::make_shared<const RotaryMotion>(m.motion(from, to, c.tcp, c.j0, c.j1));
    return mv;
}

/// Line `li` of a case: through a random point of a random pose (up to 1.3 radii from its axis),
/// along a lattice direction (even li) or a random one.
Line randomLine(const RotaryOracle& oracle, const Solid& s, std::mt19937& rng, int li) {
    std::uniform_real_distribution<double> uni(0.0, 1.0), sym(-1.0, 1.0);
    Vec3 tip, axis;
    oracle.pose(uni(rng), tip, axis);
    const Vec3 any = std::abs(axis.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    const Vec3 p = glm::normalize(glm::cross(axis, any)), q = glm::cross(axis, p);
    const double ang = 6.283185307179586 * uni(rng), rr = 1.3 * s.r * uni(rng);
    const Vec3 through = tip + axis * (s.l * uni(rng)) + (p * std::cos(ang) + q * std::sin(ang)) * rr;
    Vec3 dir(0.0);
    if (li % 2 == 0) dir[li / 2 % 3] = 1.0;
    else dir = glm::normalize(Vec3(sym(rng), sym(rng), sym(rng)));
    return Line{through, dir};
}

/// The solver's tool for the oracle's solid.
Tool solidTool(const Solid& s) { return s.ball ? ballEndMill(2 * s.r, {s.l, s.l}) : flatEndMill(2 * s.r, {s.l, s.l}); }

/// Checks `lines` random lines; returns how many points the depth check tested. `linear`, when
/// given, is set to whether the sweep searched by linear nodes (turning.cpp, note h).
int checkCase(const Case& c, const Solid& s, std::mt19937& rng, int lines, bool* linear = nullptr) {
    const Tool tool = solidTool(s);
    const Move mv = machineMove(c);
    const TurningSweep sweep(tool, mv, kEpsilon);
    if (linear) *linear = sweep.linearNodes();
    const RotaryOracle oracle(c, s);
    int checked = 0;
    for (int li = 0; li < lines; ++li) {
        const Line line = randomLine(oracle, s, rng, li);
        const std::vector<Interval> out = sweep.intersectAll(line);
        const Interval span = oracle.lineRange(line);
        for (const Interval& iv : out) {
            INFO("interval " << iv.lo << " .. " << iv.hi << " on line " << li);
            for (int k = 0; k <= 8; ++k) {
                const double t = iv.lo + (iv.hi - iv.lo) * k / 8.0;
                CHECK_FALSE(oracle.certainlyOutside(line.at(t), kEpsilon + kMargin));
            }
        }
        constexpr int kSamples = 120;
        for (int k = 0; k <= kSamples; ++k) {
            const double t = span.lo + (span.hi - span.lo) * k / kSamples;
            const bool inOut = std::any_of(out.begin(), out.end(), [&](const Interval& iv) { return iv.lo <= t && t <= iv.hi; });
            if (inOut) continue;
            const double d = oracle.depth(line.at(t));
            INFO("line " << li << " t " << t << " depth " << d);
            CHECK(d <= kEpsilon + kMargin);
            ++checked;
        }
    }
    return checked;
}

/// Finite-difference offset and the tolerances of the normals' check (turning_normals_test.cpp):
/// kNormalAngle + sqrt(2 epsilon / r), r the tool's radius (1 mm or more).
constexpr double kNormalStep = 1e-4;
constexpr double kNormalAngle = 1e-3;
constexpr double kGrazing = 0.05, kBracket = 0.05;

/// The ends the normals' check met: checked, of them marked sharp, and skipped (the oracle sees
/// them on a crease, grazing or cannot bracket them).
struct EndTally {
    int checked = 0, sharp = 0, skipped = 0;
};

/// Checks the normals at the ends of the sweep's output on `line` (number `li` of its case). As in
/// turning_normals_test.cpp, an end marked sharp claims a crease of S within the solver's rim
/// reach, and its normal, which the mesher does not take, is not checked: the oracle looks for
/// that crease with a wide stencil.
void checkEnds(const TurningSweep& sweep, const RotaryOracle& oracle, const Solid& s, const Line& line, int li,
               EndTally& t) {
    const auto in = [&](const Vec3& x) { return oracle.depth(x) >= 0.0; };
    const Vec3& dir = line.dir;
    for (const LineHit& hit : sweep.intersect(line)) {
        for (const bool hi : {false, true}) {
            const stencil::End e = stencil::bracket(hit.range, hi, kBracket);
            const std::optional<stencil::Reading> narrow = stencil::read(in, line, kNormalStep, e);
            if (!narrow || narrow->turn > stencil::kCreaseTurn) {
                ++t.skipped;
                continue;
            }
            const bool sharp = hi ? hit.sharpHi : hit.sharpLo;
            const Vec3 end = line.at(e.v);
            INFO("line " << li << (hi ? " hi" : " lo") << " end " << end.x << " " << end.y << " " << end.z
                         << (sharp ? " sharp" : "") << " turn " << narrow->turn);
            if (sharp) {
                ++t.checked, ++t.sharp;
                double wideTurn = 0.0;
                const double step = stencil::kSharpReach * kEpsilon;
                const bool near = stencil::creaseNear(in, line, kNormalStep, narrow->turn, step, e, wideTurn);
                INFO("marked sharp; the stencil of step " << step << " mm turns " << wideTurn << " rad");
                CHECK(near);
                continue;
            }
            if (std::abs(glm::dot(narrow->normal, dir)) < kGrazing) {
                ++t.skipped;
                continue;
            }
            ++t.checked;
            const Vec3 normal = hi ? hit.normalHi : hit.normalLo;
            CHECK(stencil::angle(normal, narrow->normal) <= kNormalAngle + std::sqrt(2.0 * kEpsilon / s.r) + narrow->turn);
        }
    }
}

/// Checks the normals at the ends of `lines` random lines' output (checkEnds).
void checkNormals(const Case& c, const Solid& s, std::mt19937& rng, int lines, EndTally& t) {
    const TurningSweep sweep(solidTool(s), machineMove(c), kEpsilon);
    const RotaryOracle oracle(c, s);
    for (int li = 0; li < lines; ++li) checkEnds(sweep, oracle, s, randomLine(oracle, s, rng, li), li, t);
}

/// A random move: joints from a point near the table to up to `travel` away along each axis, A
/// turning up to `turnA` degrees from [-100, -20] and C up to `turnC` from [-180, 180].
Case randomMove(std::mt19937& rng, bool tcp, const Vec3& travel, double turnA, double turnC) {
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    Case c;
    c.tcp = tcp;
    c.j0 = Vec3(20 * uni(rng), 20 * uni(rng), 5 + 10 * uni(rng));
    c.j1 = c.j0 + Vec3(travel.x * uni(rng), travel.y * uni(rng), travel.z * uni(rng));
    c.a0 = -60 + 40 * uni(rng);
    c.a1 = c.a0 + turnA * uni(rng);
    c.c0 = 180 * uni(rng);
    c.c1 = c.c0 + turnC * uni(rng);
    return c;
}

/// A random move of the head machine in identity kinematics: joints from within 15 mm of the
/// table's centre up to 6 mm away, B turning up to 20 degrees from [-30, 30], and C, if
/// `tableTurns`, up to 30 degrees from [-90, 90].
Case randomHeadMove(std::mt19937& rng, bool tableTurns) {
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    Case c;
    c.head = true;
    c.j0 = Vec3(15 * uni(rng), 15 * uni(rng), 5 * uni(rng));
    c.j1 = c.j0 + Vec3(6 * uni(rng), 6 * uni(rng), 2 * uni(rng));
    c.a0 = 30 * uni(rng);
    c.a1 = c.a0 + 20 * uni(rng);
    c.c0 = 90 * uni(rng);
    c.c1 = c.c0 + (tableTurns ? 30 * uni(rng) : 0.0);
    return c;
}

/// A ball or flat end of radius 1 to 3 mm and length 10 to 20 mm.
Solid randomSolid(std::mt19937& rng, bool ball) {
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    Solid s;
    s.ball = ball;
    s.r = 2 + uni(rng);
    s.l = 15 + 5 * uni(rng);
    return s;
}

}  // namespace

TEST_CASE("rotary sweep vs oracle: xyzac-trt moves with TCP and in identity kinematics", "[sweep][turning][machine]") {
    std::mt19937 rng(20261123);
    int checked = 0, tcpByNodes = 0, identityByNodes = 0;
    for (int i = 0; i < 24; ++i) {
        const Case c = randomMove(rng, i % 2 == 0, Vec3(8, 8, 3), 25, 60);
        const Solid s = randomSolid(rng, i % 4 >= 2);
        INFO("case " << i << (c.tcp ? " TCP" : " identity"));
        bool byNodes = false;
        checked += checkCase(c, s, rng, 6, &byNodes);
        (c.tcp ? tcpByNodes : identityByNodes) += byNodes;
    }
    CHECK(checked > 1000);
    // Identity kinematics curve the tip's path, which MotionLaw::axisPointAccelerationBound
    // bounds turn by turn: those moves take linear nodes (turning.cpp, note h) as TCP's do.
    CHECK(identityByNodes >= 6);
    CHECK(tcpByNodes >= 6);
}

TEST_CASE("rotary sweep vs oracle: moves turning a degree or two over long travel", "[sweep][turning][machine]") {
    // Small turns of A and C against 20 to 40 mm of travel, under TCP and in identity kinematics:
    // the search takes linear nodes, each a stretch of the move with the axis held (turning.cpp,
    // note h), the tables carrying the tip on a curve in identity kinematics.
    std::mt19937 rng(20261129);
    int checked = 0, linear = 0;
    for (int i = 0; i < 12; ++i) {
        const Case c = randomMove(rng, i % 3 != 0, Vec3(30, 30, 5), 2, 2);
        const Solid s = randomSolid(rng, i % 2 == 0);
        INFO("case " << i << (c.tcp ? " TCP" : " identity"));
        bool byNodes = false;
        checked += checkCase(c, s, rng, 6, &byNodes);
        linear += byNodes;
    }
    CHECK(checked > 500);
    CHECK(linear >= 8);
}

TEST_CASE("rotary sweep vs oracle: TCP moves spinning the table under a nearly upright tool",
          "[sweep][turning][machine]") {
    // A within 3 degrees of upright while C turns up to 40: the tool turns about its own axis
    // far faster than its axis turns, which only the axis's turn bounds (MotionLaw::axisTurnBound,
    // turning.cpp notes a and h). Short travel, as on real programs.
    std::mt19937 rng(20261129);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    int checked = 0, linear = 0;
    for (int i = 0; i < 12; ++i) {
        Case c = randomMove(rng, true, Vec3(3, 3, 1), 0, 40);
        c.a0 = 3 * uni(rng), c.a1 = 3 * uni(rng);
        const Solid s = randomSolid(rng, i % 2 == 0);
        INFO("case " << i);
        bool byNodes = false;
        checked += checkCase(c, s, rng, 8, &byNodes);
        linear += byNodes;
    }
    CHECK(checked > 500);
    CHECK(linear >= 6);
}

TEST_CASE("rotary sweep vs oracle: a rotary table alone turning under a still tool", "[sweep][turning][machine]") {
    // C turns 90 degrees at A = 0 in identity kinematics: the axis stays +z while the tip runs on
    // a quarter circle of radius |(10, 5)| about the C axis (turns() holds, the axes are equal).
    std::mt19937 rng(7);
    Case c;
    c.j0 = c.j1 = Vec3(10, 5, 2);
    c.a0 = c.a1 = 0;
    c.c0 = 0, c.c1 = 90;
    Solid s;
    const Move mv = machineMove(c);
    CHECK(mv.turns());
    CHECK(glm::length(*mv.startAxis - mv.axis) < 1e-15);
    CHECK(checkCase(c, s, rng, 30) > 1000);
}

TEST_CASE("rotary sweep vs oracle: a zero-length move that only tilts A", "[sweep][turning][machine]") {
    std::mt19937 rng(11);
    for (const bool tcp : {true, false}) {
        Case c;
        c.tcp = tcp;
        c.j0 = c.j1 = Vec3(-4, 12, 6);
        c.a0 = 0, c.a1 = -45;
        c.c0 = c.c1 = 30;
        Solid s;
        s.ball = true;
        CHECK(checkCase(c, s, rng, 30) > 1000);
    }
}

TEST_CASE("rotary sweep vs oracle: a head that turns in identity kinematics", "[sweep][turning][machine]") {
    // The head's pivot travels with the joints and the tool swings about it: the tip runs on an
    // arc of radius 40 about the moving pivot while the table turns under it.
    std::mt19937 rng(20261124);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    int checked = 0, byNodes = 0;
    for (int i = 0; i < 12; ++i) {
        const Case c = randomHeadMove(rng, i % 3 != 0);  // a third with the head alone turning
        Solid s;
        s.ball = i % 2 == 1;
        s.r = 2 + uni(rng);
        s.l = 15 + 5 * uni(rng);
        const Move mv = machineMove(c);
        REQUIRE(mv.rotary);
        CHECK_FALSE(mv.rotary->headTurns.empty());
        INFO("case " << i);
        bool linear = false;
        checked += checkCase(c, s, rng, 6, &linear);
        byNodes += linear;
    }
    CHECK(checked > 500);
    // MotionLaw bounds the acceleration down the heads' chain too: these moves take linear
    // nodes (turning.cpp, note h).
    CHECK(byNodes == 12);
}

TEST_CASE("rotary sweep normals vs oracle: TCP, identity kinematics and a turning head", "[sweep][turning][machine]") {
    std::mt19937 rng(20261203);
    EndTally t;
    for (int i = 0; i < 18; ++i) {
        const Case c = i % 3 == 2 ? randomHeadMove(rng, true)
                                  : randomMove(rng, i % 3 == 0, i % 2 ? Vec3(30, 30, 5) : Vec3(8, 8, 3), 25, 60);
        const Solid s = randomSolid(rng, i % 4 >= 2);
        INFO("case " << i << (c.head ? " head" : c.tcp ? " TCP" : " identity"));
        checkNormals(c, s, rng, 8, t);
    }
    INFO(t.checked << " ends checked, " << t.skipped << " skipped");
    CHECK(t.checked > 150);
    CHECK(t.skipped <= t.checked / 5);
}

TEST_CASE("rotary sweep normals vs oracle: an end near the first pose's rim is marked sharp, with a crease near",
          "[sweep][turning][machine]") {
    // A flat end on the head machine in identity kinematics, met by a line whose lower end lies on
    // the first pose's bottom, 2.8 tolerances from its rim, where both faces retreat: the rim is a
    // crease of S within the solver's rim reach, and the end is marked sharp with the bisector of
    // the faces' normals, 45 degrees off the face it lies on (found by running the normals'
    // family on other seeds). The wide stencil sees the crease.
    Case c;
    c.head = true;
    c.j0 = Vec3(6.4941719522141153, -10.938914567239491, -4.8348384018769188);
    c.j1 = Vec3(7.5276569332177088, -5.8129761074760093, -5.9489853080936639);
    c.a0 = 0.4981001699424259, c.a1 = -7.7447220473045846;
    c.c0 = -85.219933795896907, c.c1 = -101.49830927455996;
    Solid s;
    s.r = 2.2626105604235276, s.l = 10.029556694209054;
    const Line line{Vec3(9.6096111403743283, 9.4788045891140076, -1.7999197319562783),
                    Vec3(-0.45321125777987814, 0.41923480093376125, -0.78666494615408555)};
    const TurningSweep sweep(solidTool(s), machineMove(c), kEpsilon);
    EndTally t;
    checkEnds(sweep, RotaryOracle(c, s), s, line, 0, t);
    CHECK(t.sharp == 1);
    CHECK(t.checked == 2);
}
