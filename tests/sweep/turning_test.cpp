// The box of a move whose tool axis turns, against poses sampled along the turn: every sampled
// point of the tool's cylinder (or of a band of it above the tip, as a shank's) lies inside the
// box, and the box is the tip's segment box plus the sampled box of the same turn made in place,
// to within the sampling's shortfall; a machine's rotary move's box holds its sampled poses. And the linear
// nodes a turning sweep keeps (turning.cpp, note h): counted, given back, and past the budget
// made per query with the same answers; and a long cutter's bands (note i) with the Hermite data
// of the ends they make.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <thread>
#include <tuple>
#include <utility>
#include <variant>
#include <vector>

#include "dexelmill/error.h"
#include "dexelmill/machine/kinematics.h"
#include "dexelmill/path/motion.h"
#include "dexelmill/sweep/turning.h"
#include "dexelmill/tool/builders.h"
#include "sweep/interpolation.h"
#include "support/trt_kinematics.h"
#include "sweep/turning_levels.h"

using namespace dexelmill;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// The axis after turning `from` by `angle` about the unit vector `about` (Rodrigues' formula).
Vec3 rotated(const Vec3& from, const Vec3& about, double angle) {
    return from * std::cos(angle) + glm::cross(about, from) * std::sin(angle) +
           about * glm::dot(about, from) * (1.0 - std::cos(angle));
}

/// The box of a cylinder of radius r at heights [z0, l] above the tip, sampled at `poses` poses
/// of the move and `around` points on each of its two rims (the farthest points of a cylinder
/// along any direction lie on a rim).
Box sampledBox(const Move& m, double z0, double l, double r, int poses, int around) {
    const Vec3 a0 = m.startAxis ? *m.startAxis : m.axis;
    const Vec3 cross = glm::cross(a0, m.axis);
    const double angle = std::atan2(glm::length(cross), glm::dot(a0, m.axis));
    const Vec3 about = glm::length(cross) > 0 ? glm::normalize(cross) : Vec3(0.0);
    Box box;
    for (int k = 0; k <= poses; ++k) {
        const double u = double(k) / poses;
        const Vec3 a = glm::length(cross) > 0 ? rotated(a0, about, u * angle) : a0;
        const Vec3 tip = m.start + u * (m.end - m.start);
        const Vec3 any = std::abs(a.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
        const Vec3 p = glm::normalize(glm::cross(a, any)), q = glm::cross(a, p);
        for (int j = 0; j < around; ++j) {
            const double phi = 2 * kPi * j / around;
            const Vec3 rim = r * (std::cos(phi) * p + std::sin(phi) * q);
            box.expand(tip + z0 * a + rim);
            box.expand(tip + l * a + rim);
        }
    }
    return box;
}

}  // namespace

TEST_CASE("turning move box: holds and touches every pose of the cylinder, on random turns", "[sweep][turning]") {
    std::mt19937 rng(20261123);
    std::uniform_real_distribution<double> coord(-50, 50), unit(-1, 1), size(0.5, 60);
    auto direction = [&] {
        for (;;) {
            const Vec3 v(unit(rng), unit(rng), unit(rng));
            if (glm::length(v) > 0.1 && glm::length(v) <= 1) return glm::normalize(v);
        }
    };
    for (int trial = 0; trial < 300; ++trial) {
        Move m;
        m.start = Vec3(coord(rng), coord(rng), coord(rng));
        // Some moves turn in place, as a zero-length move.
        m.end = trial % 5 == 0 ? m.start : Vec3(coord(rng), coord(rng), coord(rng));
        m.axis = direction();
        Vec3 a0 = direction();
        if (glm::dot(a0, m.axis) < -0.999) a0 = -a0;
        // Every few trials the turn passes through a lattice direction or is tiny.
        if (trial % 7 == 1) a0 = glm::normalize(Vec3(0, 0, 1) - (m.axis - Vec3(0, 0, 1)));
        if (trial % 11 == 2) a0 = glm::normalize(m.axis + Vec3(1e-7, 0, 0));
        m.startAxis = a0;
        const double l = size(rng), r = 0.1 * size(rng);
        // Every third cylinder starts above the tip, as a shank does.
        const double z0 = trial % 3 == 0 ? 0.0 : l * (trial % 3) / 4.0;
        INFO("trial " << trial << ", heights " << z0 << " to " << l);
        const Box box = turningMoveBox(m, z0, l, r);
        const Box sampled = sampledBox(m, z0, l, r, 2000, 720);
        Move inPlace = m;
        inPlace.start = inPlace.end = Vec3(0.0);
        const Box turn = sampledBox(inPlace, z0, l, r, 2000, 720);
        // Sampling falls short of the extremes by at most (l + r) (pi / 2000)^2 / 2 along the
        // turn and r (2 pi / 720)^2 / 2 around the rim: below 1e-4 (l + r).
        const double slack = 1e-4 * (l + r);
        for (int i = 0; i < 3; ++i) {
            CHECK(box.lo[i] <= sampled.lo[i] + 1e-9);
            CHECK(box.hi[i] >= sampled.hi[i] - 1e-9);
            const double tipLo = std::min(m.start[i], m.end[i]), tipHi = std::max(m.start[i], m.end[i]);
            CHECK(box.lo[i] >= tipLo + turn.lo[i] - slack);
            CHECK(box.hi[i] <= tipHi + turn.hi[i] + slack);
        }
    }
}

namespace {

/// Points of a tool's meridian profile, (height, radius): each cone piece's ends and each arc at
/// `perArc` angles, from the pieces' own definitions (profile.h).
std::vector<std::pair<double, double>> profilePoints(const Tool& tool, int perArc) {
    std::vector<std::pair<double, double>> points;
    for (const ProfilePiece& piece : tool.pieces()) {
        if (const auto* c = std::get_if<ConePiece>(&piece)) {
            points.push_back({c->z0, c->r0});
            points.push_back({c->z1, c->r1});
            continue;
        }
        const ArcPiece& a = std::get<ArcPiece>(piece);
        const double t0 = std::asin(std::clamp((a.z0 - a.zc) / a.rho, -1.0, 1.0));
        const double t1 = std::asin(std::clamp((a.z1 - a.zc) / a.rho, -1.0, 1.0));
        for (int k = 0; k <= perArc; ++k) {
            const double t = t0 + (t1 - t0) * k / perArc;
            points.push_back({a.zc + a.rho * std::sin(t), a.rc + a.rho * std::cos(t)});
        }
    }
    return points;
}

/// Grows `box` by the circles of `points` (height s, radius r about the axis) at one pose: a
/// circle's extent along coordinate i is s a_i plus or minus r sqrt(1 - a_i^2).
void addPose(Box& box, const Vec3& tip, const Vec3& axis, const std::vector<std::pair<double, double>>& points) {
    for (const auto& [s, r] : points)
        for (int i = 0; i < 3; ++i) {
            const double across = r * std::sqrt(std::max(0.0, 1.0 - axis[i] * axis[i]));
            box.lo[i] = std::min(box.lo[i], tip[i] + s * axis[i] - across);
            box.hi[i] = std::max(box.hi[i], tip[i] + s * axis[i] + across);
        }
}

}  // namespace

TEST_CASE("turning move box: a tool's own profile, held and touched at every pose", "[sweep][turning]") {
    // Ball, bull nose, tapered, tapered ball, chamfer, drill and APT cutters, whole, the region
    // above their flutes, and thin bands of a ball's and a fillet's arcs: the box of ToolReach
    // holds the profile at 600 poses of each move and, for a turn in place, touches it. The samples miss the extremes by at most 60 (pi / 600)^2 / 2
    // along a turn and 10 (pi / 400)^2 / 2 around an arc: below 1e-3 mm. A cylinder's box (the
    // tool's widest radius over its heights) reaches up to a radius times the tilt's sine beyond
    // a ball's tip.
    const std::vector<Tool> tools = {ballEndMill(6.0, {20.0, 30.0}),
                                     bullNoseEndMill(10.0, 2.0, {25.0, 40.0}),
                                     taperEndMill(2.0, 0.1, {20.0, 30.0}),
                                     taperBallMill(3.0, 0.1, {20.0, 30.0}),
                                     chamferMill(1.0, 0.785, 8.0, {20.0, 30.0}),
                                     drill(8.0, 2.06, {30.0, 40.0}),
                                     aptCutter(16, 3, 5, 3, 0, 0, 50),
                                     aptCutter(10, 0, 5, 1.5, 20 * kPi / 180, 5 * kPi / 180, 30),
                                     // Cut below a ball's equator and within a fillet: an arc's
                                     // centre reaches only along its own normals.
                                     ballEndMill(6.0, {20.0, 30.0}).region(0.0, 2.0),
                                     bullNoseEndMill(10.0, 2.0, {25.0, 40.0}).region(0.5, 1.0)};
    std::mt19937 rng(20261201);
    std::uniform_real_distribution<double> coord(-50, 50), unit(-1, 1);
    const auto direction = [&] {
        for (;;) {
            const Vec3 v(unit(rng), unit(rng), unit(rng));
            if (glm::length(v) > 0.1 && glm::length(v) <= 1) return glm::normalize(v);
        }
    };
    const Machine ac = loadMachine("xyzac-trt");
    for (std::size_t k = 0; k < tools.size(); ++k) {
        for (const bool shank : {false, true}) {
            if (shank && tools[k].cuttingLength() >= tools[k].totalLength()) continue;  // all flutes
            const Tool tool =
                shank ? tools[k].region(tools[k].cuttingLength(), tools[k].totalLength()) : tools[k];
            const std::vector<std::pair<double, double>> points = profilePoints(tool, 400);
            const ToolReach reach(tool);
            // A coordinate of a unit axis rounded just past 1 is 1 (along the axis: its top, and
            // against it: its bottom).
            CHECK(reach.along(std::nextafter(1.0, 2.0), std::nextafter(1.0, 2.0)) == reach.along(1.0, 1.0));
            CHECK(reach.along(std::nextafter(-1.0, -2.0), -1.0) == reach.along(-1.0, -1.0));
            CHECK(reach.along(1.0, 1.0) == Approx(tool.totalLength()));
            CHECK(reach.along(-1.0, -1.0) == Approx(-tool.bottom()));
            for (int trial = 0; trial < 5; ++trial) {
                Move m;
                m.start = Vec3(coord(rng), coord(rng), coord(rng));
                m.end = trial == 0 ? m.start : Vec3(coord(rng), coord(rng), coord(rng));
                m.axis = direction();
                Vec3 a0 = direction();
                if (glm::dot(a0, m.axis) < 0.0) a0 = -a0;
                m.startAxis = a0;
                RotaryAngles from, to;
                from['A'] = 60 * unit(rng), from['C'] = 180 * unit(rng);
                to['A'] = from['A'] + 20 * unit(rng), to['C'] = from['C'] + 40 * unit(rng);
                // The last two trials a machine's rotary moves: with TCP, the tip on the line, and
                // without, the joints on theirs (m.start and m.end then the joints).
                const bool rotary = trial >= 3, tcp = trial == 3;
                const Vec3 j0 = m.start, j1 = m.end;
                if (rotary) {
                    m.rotary = std::make_shared<const RotaryMotion>(ac.motion(from, to, tcp, j0, j1));
                    if (!tcp) m.start = ac.partFromJoints(j0, from), m.end = ac.partFromJoints(j1, to);
                }
                INFO(tool.description() << (shank ? ", above the flutes" : "") << ", trial " << trial);
                const Box box = turningMoveBox(m, reach);
                const Vec3 cross = glm::cross(a0, m.axis);
                const double angle = std::atan2(glm::length(cross), glm::dot(a0, m.axis));
                Box seen, inPlace;
                for (int j = 0; j <= 600; ++j) {
                    const double u = j / 600.0;
                    const double a = from['A'] + u * (to['A'] - from['A']), c = from['C'] + u * (to['C'] - from['C']);
                    const Vec3 axis = rotary ? testing::xyzacAxis(a, c) : rotated(a0, glm::normalize(cross), u * angle);
                    const Vec3 joints = j0 + u * (j1 - j0);
                    addPose(seen, rotary && !tcp ? testing::xyzacForward(joints, a, c) : joints, axis, points);
                    addPose(inPlace, Vec3(0.0), axis, points);
                }
                for (int i = 0; i < 3; ++i) {
                    CHECK(box.lo[i] <= seen.lo[i] + 1e-9);
                    CHECK(box.hi[i] >= seen.hi[i] - 1e-9);
                    // A great circle's box is the tip's plus the turn in place's; a rotary move's
                    // reaches 1e-3 mm beyond its sampled poses (turning_box.cpp).
                    const double tipLo = std::min(j0[i], j1[i]), tipHi = std::max(j0[i], j1[i]);
                    const Box& near = rotary ? seen : inPlace;
                    CHECK(box.lo[i] >= (rotary ? 0.0 : tipLo) + near.lo[i] - 2e-3);
                    CHECK(box.hi[i] <= (rotary ? 0.0 : tipHi) + near.hi[i] + 2e-3);
                }
            }
        }
    }
}

TEST_CASE("turning move box: fixed axes, a turn through +z and opposite axes", "[sweep][turning]") {
    // A fixed vertical axis: the cylinder's own box.
    Move m;
    m.start = Vec3(0.0);
    m.end = Vec3(10, 0, 0);
    const Box fixed = turningMoveBox(m, 0, 50, 5);
    CHECK(fixed.lo == Vec3(-5, -5, 0));
    CHECK(fixed.hi == Vec3(15, 5, 50));
    CHECK(turnAngle(m) == 0.0);
    // Turning from 30 degrees one way to 30 the other in the xz plane: the top rim reaches
    // sqrt(50^2 + 5^2) where the axis leans atan(5 / 50), inside the turn; the bottom rim's lowest
    // point is 5 sin 30 below the tip, at either end.
    m.startAxis = Vec3(-0.5, 0, std::sqrt(0.75));
    m.axis = Vec3(0.5, 0, std::sqrt(0.75));
    CHECK(turnAngle(m) == Approx(kPi / 3));
    const Box turning = turningMoveBox(m, 0, 50, 5);
    CHECK(turning.hi.z == Approx(std::sqrt(2525.0)));
    CHECK(turning.lo.z == Approx(-2.5));
    CHECK(turning.hi.x == Approx(10 + 25 + 5 * std::sqrt(0.75)));
    CHECK(turning.lo.y == Approx(-5));
    // A band of heights [20, 50], as a shank above a 20 mm flute: its bottom rim's lowest point
    // is 20 cos 30 - 5 sin 30 above the tip, at either end; its top is the cylinder's.
    const Box band = turningMoveBox(m, 20, 50, 5);
    CHECK(band.lo.z == Approx(20 * std::sqrt(0.75) - 2.5));
    CHECK(band.hi.z == Approx(std::sqrt(2525.0)));
    CHECK(band.hi.x == Approx(turning.hi.x));
    // Opposite axes, or within kParallel of opposite: no one great circle.
    m.startAxis = Vec3(0, 0, -1);
    m.axis = Vec3(0, 0, 1);
    CHECK_THROWS_WITH(turningMoveBox(m, 0, 50, 5), Catch::Matchers::Contains("opposite"));
    m.startAxis = glm::normalize(Vec3(1e-13, 0, -1));
    CHECK_THROWS_WITH(turningMoveBox(m, 0, 50, 5), Catch::Matchers::Contains("opposite"));
    m.startAxis = glm::normalize(Vec3(1e-7, 0, -1));
    CHECK_NOTHROW(turningMoveBox(m, 0, 50, 5));
}

TEST_CASE("turning move box: a machine's rotary moves, whole tools and bands above the tip", "[sweep][turning]") {
    // The box of sampled poses padded by what the law's acceleration bound lets a tool point stray
    // holds every pose and reaches at most 1e-3 mm beyond them (turning_box.cpp): checked against
    // 4,000 poses from LinuxCNC's formulas, on turns of a hundredth of a degree to sixty, with TCP
    // and without, at heights from the tip and from above it. The poses between those samples lie
    // at most |y''| / (8 4000^2) beyond them, under 1e-5 mm here.
    const Machine ac = loadMachine("xyzac-trt");
    std::mt19937 rng(20261130);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    for (int trial = 0; trial < 36; ++trial) {
        const double turn = 0.01 * std::pow(6000.0, (trial % 9) / 8.0);  // degrees, 0.01 to 60
        RotaryAngles from, to;
        from['A'] = 60 * uni(rng), from['C'] = 180 * uni(rng);
        to['A'] = from['A'] + 0.5 * turn * uni(rng), to['C'] = from['C'] + turn * uni(rng);
        const Vec3 j0(40 * uni(rng), 40 * uni(rng), 20 * uni(rng)), j1(40 * uni(rng), 40 * uni(rng), 20 * uni(rng));
        const bool tcp = trial % 2 == 0;
        Move m;
        m.start = tcp ? j0 : ac.partFromJoints(j0, from);
        m.end = tcp ? j1 : ac.partFromJoints(j1, to);
        m.rotary = std::make_shared<const RotaryMotion>(ac.motion(from, to, tcp, j0, j1));
        const double z0 = trial % 3 == 0 ? 0.0 : 25.0, r = 5.0;
        INFO("trial " << trial << (tcp ? " TCP" : " identity") << ", turns up to " << turn << " degrees, heights "
                      << z0 << " to 40");
        const Box box = turningMoveBox(m, z0, 40.0, r);
        Box seen;
        for (int k = 0; k <= 4000; ++k) {
            // The pose from LinuxCNC's formulas, the joints and angles linear in u.
            const double u = k / 4000.0;
            const double a = from['A'] + u * (to['A'] - from['A']), c = from['C'] + u * (to['C'] - from['C']);
            const Vec3 joints = j0 + u * (j1 - j0);
            const Vec3 tip = tcp ? joints : testing::xyzacForward(joints, a, c), axis = testing::xyzacAxis(a, c);
            // The cylinder's extent along each coordinate: its rims' centres', plus r times the
            // sine of the axis's angle to that coordinate.
            for (int i = 0; i < 3; ++i) {
                const double across = r * std::sqrt(std::max(0.0, 1.0 - axis[i] * axis[i]));
                const double e0 = tip[i] + z0 * axis[i], e1 = tip[i] + 40.0 * axis[i];
                seen.lo[i] = std::min(seen.lo[i], std::min(e0, e1) - across);
                seen.hi[i] = std::max(seen.hi[i], std::max(e0, e1) + across);
            }
        }
        for (int i = 0; i < 3; ++i) {
            CHECK(box.lo[i] <= seen.lo[i]);
            CHECK(box.hi[i] >= seen.hi[i]);
            CHECK(box.lo[i] >= seen.lo[i] - 1e-3 - 1e-5);
            CHECK(box.hi[i] <= seen.hi[i] + 1e-3 + 1e-5);
        }
    }
}

TEST_CASE("turning sweep: a move its search cannot resolve to epsilon is refused", "[sweep][turning]") {
    // A tool point travelling 2^61 epsilon (4.6e14 mm at 1e-4) needs more than kMaxLevel levels;
    // one travelling 1e10 mm needs 47.
    const Tool tool = flatEndMill(6.0, {20.0, 30.0});
    Move m;
    m.axis = Vec3(0, 0, 1);
    m.startAxis = glm::normalize(Vec3(0.1, 0, 1));
    m.end = Vec3(5e14, 0, 0);
    CHECK_THROWS_WITH(TurningSweep(tool, m), Catch::Matchers::Contains("beyond what its sweep resolves"));
    m.end = Vec3(1e10, 0, 0);
    CHECK_NOTHROW(TurningSweep(tool, m));
}

TEST_CASE("turning sweep: the least of a parabola through three samples, and the node polynomial's largest",
          "[sweep][turning]") {
    // Against dense sampling of the Lagrange form, which shares no code with Newton's: the least
    // lies at the place given, no sample falls below it, and the node polynomial's largest is
    // reached and never passed. Degenerate cases: a straight line, a sample on the vertex, three
    // equal values and a middle sample next to an end.
    std::mt19937 rng(20261130);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    const auto lagrange = [](double u0, double h0, double u1, double h1, double u2, double h2, double u) {
        return h0 * (u - u1) * (u - u2) / ((u0 - u1) * (u0 - u2)) + h1 * (u - u0) * (u - u2) / ((u1 - u0) * (u1 - u2)) +
               h2 * (u - u0) * (u - u1) / ((u2 - u0) * (u2 - u1));
    };
    std::vector<std::array<double, 6>> cases = {
        {0.0, 1.0, 0.5, 0.5, 1.0, 0.0},       // a straight line: least at the lower end
        {0.0, 1.0, 0.5, 0.0, 1.0, 1.0},       // the vertex on the middle sample
        {0.25, 2.0, 0.375, 2.0, 0.5, 2.0},    // three equal values
        {0.0, 0.0, 1e-6, -1e-3, 1.0, 0.5},    // the middle next to an end
        {0.0, -1.0, 0.5, 1.0, 1.0, -2.0},     // opening downwards: least at an end
    };
    for (int i = 0; i < 200; ++i) {
        double u[3] = {uni(rng), uni(rng), uni(rng)};
        std::sort(u, u + 3);
        if (!(u[0] < u[1] && u[1] < u[2])) continue;
        cases.push_back({u[0], uni(rng), u[1], uni(rng), u[2], uni(rng)});
    }
    for (const auto& c : cases) {
        const auto [u0, h0, u1, h1, u2, h2] = c;
        INFO("samples (" << u0 << ", " << h0 << "), (" << u1 << ", " << h1 << "), (" << u2 << ", " << h2 << ")");
        const turning::ParabolaLow low = turning::parabolaLow(u0, h0, u1, h1, u2, h2);
        const double span = u2 - u0, scale = 1.0 + std::abs(h0) + std::abs(h1) + std::abs(h2);
        CHECK(low.u >= u0);
        CHECK(low.u <= u2);
        CHECK(low.value == Approx(lagrange(u0, h0, u1, h1, u2, h2, low.u)).margin(1e-9 * scale));
        double sampledLow = std::numeric_limits<double>::infinity(), sampledLargest = 0.0;
        for (int k = 0; k <= 4000; ++k) {
            const double x = u0 + span * k / 4000.0;
            sampledLow = std::min(sampledLow, lagrange(u0, h0, u1, h1, u2, h2, x));
            sampledLargest = std::max(sampledLargest, std::abs((x - u0) * (x - u1) * (x - u2)));
        }
        CHECK(sampledLow >= low.value - 1e-9 * scale);
        const double largest = turning::nodePolynomialMax(u0, u1, u2);
        CHECK(largest >= sampledLargest * (1.0 - 1e-12));
        // The sampling falls short of the largest by at most its slope times half a step.
        CHECK(largest <= sampledLargest + 3.0 * span * span * span / 8000.0 + 1e-15);
    }
}

TEST_CASE("turning sweep: a disk's plane and a cylinder stray from their parabolas through three poses by at most "
          "note o's remainders",
          "[sweep][turning]") {
    // From dense poses of MULTAX and TCP moves (turning_linear_search.cpp, note o): H_z(u) =
    // a(u).(z - p(u)) - h, the distance of a point z beyond a disk's plane at height h, and G_z(u)
    // = |z - p|^2 - (a.(z - p))^2 - R^2, how far outside a cylinder about the axis. Against the
    // parabola through
    // three poses, each strays by at most M |(u - u0)(u - u1)(u - u2)| / 6, with M from the law's
    // bounds (J >= |a'''|, K1 >= |a''|, omega >= |a'|, |f| the tip's speed, r = max |z - p|):
    // J r + 3 K1 |f| for H, 2 r (J r + 3 K1 |f|) + 6 (omega r + |f|)(K1 r + 2 omega |f|) for G. On
    // most moves each comes within a factor 50 of its remainder somewhere.
    const Machine ac = loadMachine("xyzac-trt");
    std::mt19937 rng(20261201);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    int tight[2] = {0, 0}, moves = 0;
    for (int trial = 0; trial < 60; ++trial) {
        Move m;
        m.start = Vec3(20 * uni(rng), 20 * uni(rng), 20 * uni(rng));
        m.end = m.start + 10.0 * (1.0 + uni(rng)) * Vec3(uni(rng), uni(rng), uni(rng));
        if (trial % 2 == 0) {
            m.axis = glm::normalize(Vec3(uni(rng), uni(rng), 2.0));
            m.startAxis = glm::normalize(m.axis + 0.8 * Vec3(uni(rng), uni(rng), uni(rng)));
        } else {
            RotaryAngles from, to;
            from['A'] = 40 * uni(rng), from['C'] = 90 * uni(rng);
            to['A'] = from['A'] + 30 * uni(rng), to['C'] = from['C'] + 60 * uni(rng);
            m.rotary = std::make_shared<const RotaryMotion>(ac.motion(from, to, true, m.start, m.end));
        }
        const MotionLaw law(m);
        const Vec3 z = m.start + Vec3(30 * uni(rng), 30 * uni(rng), 30 * uni(rng));
        const double h = 20.0 * (1.0 + uni(rng)), radius = 5.0 * (1.0 + uni(rng));
        const auto H = [&](double u) {
            const ToolPose p = law.pose(u);
            return glm::dot(p.axis, z - p.tip) - h;
        };
        const auto G = [&](double u) {
            const ToolPose p = law.pose(u);
            const double along = glm::dot(p.axis, z - p.tip);
            return glm::dot(z - p.tip, z - p.tip) - along * along - radius * radius;
        };
        const double r = std::max(glm::length(z - m.start), glm::length(z - m.end));
        const double J = law.axisJerkBound(), K1 = law.axisPointAccelerationBound(1.0), omega = law.axisTurnBound();
        const double f = law.speedBound(0.0);
        const double bounds[2] = {J * r + 3.0 * K1 * f,
                                  2.0 * r * (J * r + 3.0 * K1 * f) + 6.0 * (omega * r + f) * (K1 * r + 2.0 * omega * f)};
        double u[3] = {0.5 * (1.0 + uni(rng)), 0.5 * (1.0 + uni(rng)), 0.5 * (1.0 + uni(rng))};
        std::sort(u, u + 3);
        if (!(u[0] < u[1] && u[1] < u[2])) continue;
        ++moves;
        for (int which = 0; which < 2; ++which) {
            const auto F = [&](double x) { return which == 0 ? H(x) : G(x); };
            const double h0 = F(u[0]), h1 = F(u[1]), h2 = F(u[2]);
            double ratio = 0.0, excess = -1.0;
            for (int k = 0; k <= 400; ++k) {
                const double x = u[0] + (u[2] - u[0]) * k / 400.0;
                const double p2 = h0 * (x - u[1]) * (x - u[2]) / ((u[0] - u[1]) * (u[0] - u[2])) +
                                  h1 * (x - u[0]) * (x - u[2]) / ((u[1] - u[0]) * (u[1] - u[2])) +
                                  h2 * (x - u[0]) * (x - u[1]) / ((u[2] - u[0]) * (u[2] - u[1]));
                const double remainder = bounds[which] * std::abs((x - u[0]) * (x - u[1]) * (x - u[2])) / 6.0;
                excess = std::max(excess, std::abs(F(x) - p2) - remainder);
                if (remainder > 1e-6) ratio = std::max(ratio, std::abs(F(x) - p2) / remainder);
            }
            INFO("trial " << trial << (which == 0 ? ", the disk" : ", the cylinder"));
            CHECK(excess <= 1e-8);
            if (ratio >= 1.0 / 50.0) ++tight[which];
        }
    }
    CHECK(tight[0] >= moves / 2);
    CHECK(tight[1] >= moves / 2);
}

TEST_CASE("turning sweep: a node's level and width from its heap index", "[sweep][turning]") {
    // Node i's halves are 2i and 2i + 1 from the root 1: level k holds heaps [2^k, 2^(k+1)), each
    // 2^-k wide. Counted by halving, and the width by std::ldexp.
    for (const std::uint32_t heap :
         {1u, 2u, 3u, 4u, 5u, 7u, 8u, 1000u, 1023u, 1024u, (1u << 30) - 1u, 1u << 30, (1u << 31) + 5u, ~0u}) {
        int level = 0;
        for (std::uint32_t h = heap; h > 1; h /= 2) ++level;
        INFO("heap " << heap);
        CHECK(turning::heapLevel(heap) == level);
        CHECK(turning::heapWidth(heap) == std::ldexp(1.0, -level));
    }
}

namespace {

/// A 30 mm move from the origin to (30, 10, -3), its axis ending tilted towards (0.3, -0.2, 1)
/// and turning `degrees` on the way, in the plane of the tilt.
Move tiltedTurn(double degrees) {
    Move m;
    m.start = Vec3(0.0);
    m.end = Vec3(30.0, 10.0, -3.0);
    m.axis = glm::normalize(Vec3(0.3, -0.2, 1.0));
    m.startAxis = rotated(m.axis, glm::normalize(glm::cross(m.axis, Vec3(0, 0, 1))), degrees * kPi / 180.0);
    return m;
}

/// While alive, the turning sweeps may keep no linear node: each query makes its nodes and drops
/// them. The default budget comes back however the scope ends.
struct NoNodeBudget {
    NoNodeBudget() { TurningSweep::setLinearNodeBudget(0); }
    ~NoNodeBudget() { TurningSweep::setLinearNodeBudget(kDefaultLinearNodeBudget); }
    NoNodeBudget(const NoNodeBudget&) = delete;
    NoNodeBudget& operator=(const NoNodeBudget&) = delete;
};

/// How many of `lines` `sweep` hits, checking that each answer is `kept`'s to the bit: ends and
/// normals.
int sameHits(const TurningSweep& sweep, const std::vector<Line>& lines, const std::vector<std::vector<LineHit>>& kept) {
    int hits = 0;
    for (std::size_t i = 0; i < lines.size(); ++i) {
        const std::vector<LineHit> h = sweep.intersect(lines[i]);
        REQUIRE(h.size() == kept[i].size());
        for (std::size_t k = 0; k < h.size(); ++k) {
            CHECK(h[k].range.lo == kept[i][k].range.lo);
            CHECK(h[k].range.hi == kept[i][k].range.hi);
            CHECK(h[k].normalLo == kept[i][k].normalLo);
            CHECK(h[k].normalHi == kept[i][k].normalHi);
        }
        hits += !h.empty();
    }
    return hits;
}

}  // namespace

TEST_CASE("turning sweep: linear nodes are kept once, given back, and past the budget made per query",
          "[sweep][turning]") {
    // A flat end mill turning one degree over 30 mm: the tip's travel is most of the speed, so the
    // search takes linear nodes.
    const Tool tool = flatEndMill(10.0, {20.0, 20.0});
    const Move m = tiltedTurn(1.0);
    std::vector<Line> lines;
    for (int i = 0; i < 400; ++i) lines.push_back({Vec3(-20.0, -8.0 + 0.05 * i, -1.5 - 0.002 * i), Vec3(1, 0, 0)});
    for (int i = 0; i < 400; ++i) lines.push_back({Vec3(-5.0 + 0.1 * i, 3.0, -20.0), Vec3(0, 0, 1)});
    const std::size_t before = TurningSweep::keptLinearNodes();
    std::vector<std::vector<LineHit>> kept;
    std::size_t whileAlive = 0;
    {
        const TurningSweep sweep(tool, m);
        REQUIRE(sweep.linearNodes());
        for (const Line& l : lines) kept.push_back(sweep.intersect(l));
        whileAlive = TurningSweep::keptLinearNodes() - before;
        // 98 since rims and bridged gaps settle more nodes before their sweeps are made (notes k
        // and q); enough to show nodes are kept.
        CHECK(whileAlive > 50);
        CHECK(whileAlive <= sweep.linearNodeBound());
        // Asked again, the lines make no new nodes.
        for (const Line& l : lines) sweep.intersect(l);
        CHECK(TurningSweep::keptLinearNodes() - before == whileAlive);
    }
    CHECK(TurningSweep::keptLinearNodes() == before);
    // With no budget, nothing is kept and every answer is the same to the bit.
    const NoNodeBudget none;
    const TurningSweep sweep(tool, m);
    CHECK(sameHits(sweep, lines, kept) > 200);
    CHECK(TurningSweep::keptLinearNodes() == before);
}

TEST_CASE("turning sweep: a deep tree keeps its upper levels, and its bound holds what it keeps",
          "[sweep][turning]") {
    // The flat end turning ten degrees over 30 mm, within 1e-5 mm: its leaves lie at level 17
    // (omega rho / 2 = 0.98 mm over 2^17 is below epsilon; rho = hypot(10, 5)), deeper than the
    // levels a sweep keeps, so its deepest nodes are made by each query and dropped. The answers
    // must not depend on what was kept: the same lines with no budget give the same bits.
    const double epsilon = 1e-5;
    const Tool tool = flatEndMill(10.0, {20.0, 20.0});
    const Move m = tiltedTurn(10.0);
    std::vector<Line> lines;
    for (int i = 0; i < 200; ++i) lines.push_back({Vec3(-20.0, -8.0 + 0.1 * i, -1.5 - 0.004 * i), Vec3(1, 0, 0)});
    for (int i = 0; i < 200; ++i) lines.push_back({Vec3(-5.0 + 0.2 * i, 3.0, -20.0), Vec3(0, 0, 1)});
    const std::size_t before = TurningSweep::keptLinearNodes();
    std::vector<std::vector<LineHit>> kept;
    {
        const TurningSweep sweep(tool, m, epsilon);
        REQUIRE(sweep.linearNodes());
        // Its one tree cut at the deepest level kept.
        CHECK(sweep.linearNodeBound() == (std::size_t(2) << 16) - 1);
        for (const Line& l : lines) kept.push_back(sweep.intersect(l));
        const std::size_t alive = TurningSweep::keptLinearNodes() - before;
        CHECK(alive > 100);
        CHECK(alive <= sweep.linearNodeBound());
    }
    const NoNodeBudget none;
    CHECK(sameHits(TurningSweep(tool, m, epsilon), lines, kept) > 100);
}

TEST_CASE("turning sweep: a long cutter is searched in bands, and their ends take the lateral envelope's normal",
          "[sweep][turning]") {
    // A flat end mill 50 mm long turning one degree over 30 mm: cut into 8 bands (turning.cpp,
    // note i) 6.25 mm high, whose cuts lie inside the tool. Lines in random directions through
    // points of the tool's side at a cut's height, at random poses, meet the lateral envelope
    // there (and elsewhere). Its normal is across the axis of the pose that makes it, so within
    // the turn of the axis at the move's middle; a cut face's normal would lie along it. Ends
    // more than 6 mm from the ends of the tool at the middle pose lie on the lateral envelope
    // whatever pose made them (the tip travels 3.8 mm along the axis). The answers with no node
    // budget are the same to the bit.
    const Tool tool = flatEndMill(10.0, {50.0, 50.0});
    const Move m = tiltedTurn(1.0);
    const TurningSweep sweep(tool, m);
    REQUIRE(sweep.linearNodes());
    CHECK(sweep.linearBands() == 8);
    const ToolPose middle = sweep.pose(0.5);
    std::mt19937_64 rng(20261129);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::normal_distribution<double> gauss;
    std::vector<Line> lines;
    for (int i = 0; i < 3000; ++i) {
        const ToolPose p = sweep.pose(uniform(rng));
        const Vec3 dir = glm::normalize(Vec3(gauss(rng), gauss(rng), gauss(rng)));
        const Vec3 out = glm::normalize(glm::cross(p.axis, glm::cross(p.axis, dir)));
        const double height = 6.25 * (1 + int(uniform(rng) * 7)) + 0.02 * (uniform(rng) - 0.5);
        lines.push_back({p.tip + height * p.axis + 5.0 * out - 40.0 * dir, dir});
    }
    const double turn = std::sin(kPi / 180.0);
    std::vector<std::vector<LineHit>> kept;
    int lateral = 0;
    for (const Line& l : lines) {
        kept.push_back(sweep.intersect(l));
        for (const LineHit& h : kept.back())
            for (const auto& [t, n, sharp] :
                 {std::tuple(h.range.lo, h.normalLo, h.sharpLo), std::tuple(h.range.hi, h.normalHi, h.sharpHi)}) {
                const double z = glm::dot(l.at(t) - middle.tip, middle.axis);
                if (z < 6.0 || z > 44.0) continue;
                INFO("line " << &l - lines.data() << " end t = " << t << " height " << z);
                CHECK(std::abs(glm::length(n) - 1.0) <= 1e-9);
                CHECK(std::abs(glm::dot(n, middle.axis)) <= turn + 1e-3);
                CHECK_FALSE(sharp);
                ++lateral;
            }
    }
    CHECK(lateral > 2000);
    const NoNodeBudget none;
    CHECK(sameHits(TurningSweep(tool, m), lines, kept) > 2000);
}

TEST_CASE("turning sweep: a ball end's lines asked first on a fresh thread", "[sweep][turning]") {
    // The search keeps the poses it solves per thread, and the Hermite data of an end that the
    // first or last pose made comes from what it found there; an end a ball's capsules made is
    // not among those. Each line is asked on a thread of its own, where it is the first query,
    // and on this thread after the others: the same answers, to the bit. (Taking a capsule's end
    // for an end pose's once read the poses of a thread that had solved none, and crashed.)
    const Tool tool = ballEndMill(6.0, {30.0, 30.0});
    const TurningSweep sweep(tool, tiltedTurn(10.0));
    std::mt19937_64 rng(20261130);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::normal_distribution<double> gauss;
    int ends = 0;
    for (int i = 0; i < 40; ++i) {
        const ToolPose p = sweep.pose(uniform(rng));
        const Vec3 dir = glm::normalize(Vec3(gauss(rng), gauss(rng), gauss(rng)));
        const Vec3 side = glm::normalize(glm::cross(p.axis, dir));
        const Line line{p.tip + 3.0 * uniform(rng) * p.axis + 2.0 * uniform(rng) * side - 40.0 * dir, dir};
        std::vector<LineHit> first;
        std::thread([&] { first = sweep.intersect(line); }).join();
        const std::vector<LineHit> later = sweep.intersect(line);
        INFO("line " << i);
        REQUIRE(first.size() == later.size());
        for (std::size_t k = 0; k < later.size(); ++k) {
            CHECK(first[k].range.lo == later[k].range.lo);
            CHECK(first[k].range.hi == later[k].range.hi);
            CHECK(first[k].normalLo == later[k].normalLo);
            CHECK(first[k].normalHi == later[k].normalHi);
            CHECK(first[k].sharpLo == later[k].sharpLo);
            CHECK(first[k].sharpHi == later[k].sharpHi);
            ends += 2;
        }
    }
    CHECK(ends >= 40);
}

namespace {

/// While alive, the Hermite data of the first and last poses' ends are found afresh
/// (TurningSweep::setEndNormalsFromSearch); the default comes back however the scope ends.
struct EndNormalsAfresh {
    EndNormalsAfresh() { TurningSweep::setEndNormalsFromSearch(false); }
    ~EndNormalsAfresh() { TurningSweep::setEndNormalsFromSearch(true); }
    EndNormalsAfresh(const EndNormalsAfresh&) = delete;
    EndNormalsAfresh& operator=(const EndNormalsAfresh&) = delete;
};

}  // namespace

TEST_CASE("turning sweep: the end poses' Hermite data from the search are those found afresh",
          "[sweep][turning]") {
    // An output end that the first or last pose made takes the normal of the face the search's
    // crossing found there, where no other face lies within the rim reach (4 tolerances); the
    // Hermite data found afresh at that pose are the same. Lines through points of the end
    // poses' surfaces, on their rims, 4 tolerances off them and elsewhere, along the lattice and
    // in random directions, for tools with rims of several kinds and turns from 0.05 to 30
    // degrees: the same intervals and sharp flags, and normals within rounding (a compiler that
    // fuses multiply-adds may round the two ways differently).
    const std::vector<Tool> tools{flatEndMill(6.0, {20.0, 30.0}),
                                  bullNoseEndMill(10.0, 2.0, {25.0, 30.0}),
                                  taperEndMill(4.0, 0.1, {20.0, 30.0}),
                                  chamferMill(1.0, 0.6, 10.0, {20.0, 30.0}),
                                  drill(6.0, 118.0 * kPi / 180.0, {30.0, 40.0}),
                                  flatEndMill(10.0, {50.0, 50.0})};
    std::mt19937_64 rng(20261130);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::normal_distribution<double> gauss;
    const auto direction = [&] { return glm::normalize(Vec3(gauss(rng), gauss(rng), gauss(rng))); };
    const double eps = kDefaultTurnTolerance;
    int ends = 0, onRims = 0;
    for (const Tool& tool : tools) {
        for (const double degrees : {0.05, 0.6, 5.0, 30.0}) {
            for (const double travel : {0.0, 0.5, 30.0}) {
                Move m;
                m.start = Vec3(gauss(rng), gauss(rng), gauss(rng));
                m.end = m.start + travel * direction();
                m.axis = glm::normalize(Vec3(0.3 * gauss(rng), 0.3 * gauss(rng), 1.0));
                m.startAxis = rotated(m.axis, glm::normalize(glm::cross(m.axis, direction())), degrees * kPi / 180.0);
                const TurningSweep sweep(tool, m);
                const double length = tool.totalLength(), far = 2.0 * (length + tool.maxRadius());
                for (int i = 0; i < 60; ++i) {
                    const ToolPose p = sweep.pose(i % 5 == 4 ? uniform(rng) : double(i % 2));
                    const Vec3 any = std::abs(p.axis.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
                    const Vec3 e1 = glm::normalize(glm::cross(p.axis, any)), e2 = glm::cross(p.axis, e1);
                    const double phi = 2.0 * kPi * uniform(rng);
                    const Vec3 radial = std::cos(phi) * e1 + std::sin(phi) * e2;
                    // A height on the tool, or its bottom face's (a rim there), or 4 tolerances
                    // above or below it; a radius on the surface there, or 4 tolerances off it,
                    // or the axis (the tip, about which a move without travel turns the tool: a
                    // line through it ends there at every pose, and a middle pose may make an
                    // end exactly where an end pose's lies).
                    double z = i % 3 == 0 ? 0.0 : length * uniform(rng);
                    if (i % 7 == 0) z += (i % 2 ? 4.0 : -4.0) * eps;
                    double r = std::max(0.0, tool.radiusAt(std::max(z, 0.0)));
                    if (i % 3 == 1) r += (i % 2 ? 4.0 : -4.0) * eps * (1.0 + 0.1 * gauss(rng));
                    if (i % 11 == 0) r = 0.0;
                    onRims += i % 3 == 0;
                    const Vec3 point = p.tip + z * p.axis + r * radial;
                    const Vec3 dir = i % 4 < 3 ? Vec3(i % 4 == 0, i % 4 == 1, i % 4 == 2) : direction();
                    const Line line{point - far * dir, dir};
                    const std::vector<LineHit> fromSearch = sweep.intersect(line);
                    std::vector<LineHit> afresh;
                    {
                        const EndNormalsAfresh scope;
                        afresh = sweep.intersect(line);
                    }
                    INFO("tool " << tool.description() << ", turn " << degrees << " degrees, travel " << travel
                                 << ", line " << i);
                    REQUIRE(fromSearch.size() == afresh.size());
                    for (std::size_t k = 0; k < afresh.size(); ++k) {
                        CHECK(fromSearch[k].range.lo == afresh[k].range.lo);
                        CHECK(fromSearch[k].range.hi == afresh[k].range.hi);
                        CHECK(glm::length(fromSearch[k].normalLo - afresh[k].normalLo) <= 1e-12);
                        CHECK(glm::length(fromSearch[k].normalHi - afresh[k].normalHi) <= 1e-12);
                        CHECK(fromSearch[k].sharpLo == afresh[k].sharpLo);
                        CHECK(fromSearch[k].sharpHi == afresh[k].sharpHi);
                        ends += 2;
                    }
                }
            }
        }
    }
    CHECK(ends > 4000);
    CHECK(onRims > 1000);
}

TEST_CASE("turning sweep: Hermite data only for the ends within the care", "[sweep][turning]") {
    // The cutting loop passes a dexel's material as the care: an end outside it meets no
    // material, and its Hermite data are left zero. A care that holds the whole bound changes
    // nothing, to the bit; one that stops inside the first interval leaves that interval's upper
    // end (and every end past it) without them, and gives the others theirs.
    const Tool tool = flatEndMill(10.0, {50.0, 50.0});
    const TurningSweep sweep(tool, tiltedTurn(1.0));
    std::mt19937_64 rng(20261130);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::normal_distribution<double> gauss;
    int inside = 0, outside = 0;
    for (int i = 0; i < 500; ++i) {
        const ToolPose p = sweep.pose(uniform(rng));
        const Vec3 dir = glm::normalize(Vec3(gauss(rng), gauss(rng), gauss(rng)));
        const Vec3 side = glm::normalize(glm::cross(p.axis, dir));
        const Line line{p.tip + 50.0 * uniform(rng) * p.axis + 4.0 * side - 40.0 * dir, dir};
        const std::vector<LineHit> all = sweep.intersect(line);
        if (all.empty()) continue;
        const Interval reach = sweep.bound(line);
        const std::vector<LineHit> whole = sweep.intersect(line, {reach});
        REQUIRE(whole.size() == all.size());
        for (std::size_t k = 0; k < all.size(); ++k) {
            CHECK(whole[k].range.lo == all[k].range.lo);
            CHECK(whole[k].range.hi == all[k].range.hi);
            CHECK(whole[k].normalLo == all[k].normalLo);
            CHECK(whole[k].normalHi == all[k].normalHi);
        }
        const Interval care{reach.lo, 0.5 * (all[0].range.lo + all[0].range.hi)};
        for (const LineHit& h : sweep.intersect(line, {care}))
            for (const auto& [t, n, sharp] :
                 {std::tuple(h.range.lo, h.normalLo, h.sharpLo), std::tuple(h.range.hi, h.normalHi, h.sharpHi)}) {
                INFO("line " << i << " end t = " << t << ", care [" << care.lo << ", " << care.hi << "]");
                if (care.contains(t)) {
                    CHECK(std::abs(glm::length(n) - 1.0) <= 1e-9);
                    ++inside;
                } else {
                    CHECK(n == Vec3(0.0));
                    CHECK_FALSE(sharp);
                    ++outside;
                }
            }
    }
    CHECK(inside > 200);
    CHECK(outside > 200);
}
