// TurningSweep (a move whose tool axis turns) against the brute-force oracle of turning_oracle.h,
// which shares no code with the solver. Fixed seeds; case counts scale with DEXELMILL_TEST_SCALE.
//
// What is checked, for a unit-direction line and the union O of sweep.intersectAll(line):
//  0. O is sorted and disjoint, and bound(line) holds every interval of it.
//  1. O lies within eps of S: no output point (both ends of each interval and three inner points)
//     is certainly farther than eps + kRounding from S. (The sweep joins two of its intervals
//     where the gap between them lies within eps of its poses; elsewhere O is inside S.)
//  2. Every point of the line deeper than eps inside some T(u) lies in O: no test point outside O
//     (a grid along the line and points just beyond each end of O) has a pose u at which the
//     oracle certifies it deeper than eps + kRounding.
// Both checks fail only on a certificate, so the oracle can never fail a correct solver; where it
// cannot decide, it passes.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "dexelmill/error.h"
#include "turning_oracle.h"

using namespace turning_oracle;

namespace {

// ---- Checks ---------------------------------------------------------------------------------

struct Tally {
    int cases = 0, hits = 0, failures = 0;
    int linear = 0;  ///< cases the sweep searched by linear nodes (turning.cpp, note h)
    std::string log;

    void fail(const Case& c, const std::string& what) {
        if (++failures <= 5) log += "FAIL case #" + std::to_string(cases - 1) + ": " + what + "\n   " + describe(c) + "\n";
    }
};

/// Offsets (mm) beyond each end of O at which check 2 also looks: where a solver that stops
/// short of the sweep's boundary by more than epsilon leaves deep points.
constexpr double kEndOffsets[] = {2e-4, 1e-3, 1e-2, 1e-1, 1.0};
/// Check 2's grid along the line's reach, and check 1's points inside each interval.
constexpr int kLineGrid = 64;
constexpr double kInnerFractions[] = {0.25, 0.5, 0.75};

/// Runs checks 0 to 2 on one case; returns the solver's output. With a `care` (sorted, disjoint),
/// the sweep is asked for that alone, and check 2 looks only inside it, where guarantee 2 holds.
std::vector<Interval> checkCase(const Case& c, Tally& tally, std::mt19937_64& rng, const std::vector<Interval>& care = {}) {
    ++tally.cases;
    const TurningSweep sweep(c.model->tool, c.move, c.epsilon);
    if (sweep.linearNodes()) ++tally.linear;
    const SweepOracle o(c.model->parts, c.move);
    std::vector<Interval> out;
    for (const LineHit& h : sweep.intersect(c.line, care)) out.push_back(h.range);
    if (!out.empty()) ++tally.hits;
    std::ostringstream got;
    got << std::setprecision(17) << "output " << cases::str(out);

    // 0. Structure.
    const Interval bound = sweep.bound(c.line);
    for (std::size_t k = 0; k < out.size(); ++k) {
        if (!(out[k].lo <= out[k].hi) || (k > 0 && !(out[k - 1].hi < out[k].lo)))
            tally.fail(c, "output not sorted and disjoint: " + got.str());
        if (!(bound.lo <= out[k].lo && out[k].hi <= bound.hi)) {
            std::ostringstream s;
            s << std::setprecision(17) << "bound(line) [" << bound.lo << ", " << bound.hi << "] misses an interval: " << got.str();
            tally.fail(c, s.str());
        }
    }

    // 1. O within eps of S (the sweep joins gaps whose points lie within eps of its poses).
    const double margin = sweep.epsilon() + kRounding;
    for (const Interval& iv : out) {
        std::vector<double> ts{iv.lo, iv.hi};
        for (double s : kInnerFractions) ts.push_back(iv.lo + s * (iv.hi - iv.lo));
        for (double t : ts) {
            const Vec3 x = c.line.at(t);
            if (o.certainlyOutside(x, margin)) {
                std::ostringstream s;
                s << std::setprecision(17) << "check 1: output point t = " << t << " is certainly more than " << margin
                  << " mm outside the sweep; " << o.nearest(x) << "; " << got.str();
                tally.fail(c, s.str());
            }
        }
    }

    // 2. Points deeper than epsilon in O.
    auto inO = [&](double t) {
        for (const Interval& iv : out)
            if (iv.contains(t)) return true;
        return false;
    };
    std::vector<double> ts;
    const double jitter = cases::uniform(rng, 0, 1);
    for (const Interval& range : care.empty() ? std::vector<Interval>{o.lineRange(c.line)} : care)
        for (int i = 0; i < kLineGrid; ++i) ts.push_back(range.lo + (i + jitter) / kLineGrid * range.length());
    for (const Interval& iv : out)
        for (double d : kEndOffsets) ts.push_back(iv.lo - d), ts.push_back(iv.hi + d);
    const double depth = sweep.epsilon() + kRounding;
    for (double t : ts) {
        if (inO(t)) continue;
        if (!care.empty() && std::none_of(care.begin(), care.end(), [t](const Interval& w) { return w.contains(t); }))
            continue;
        const Vec3 x = c.line.at(t);
        if (const auto u = o.deepWitness(x, depth)) {
            std::ostringstream s;
            s << std::setprecision(17) << "check 2: t = " << t << " is certified deeper than " << depth
              << " mm inside T(u) at u = " << *u << " but not in the output; " << o.nearest(x) << "; " << got.str();
            tally.fail(c, s.str());
        }
    }
    return out;
}

void report(const Tally& t, bool requireHits = true) {
    INFO(t.cases << " cases (" << t.linear << " by linear nodes), " << t.hits << " with output, " << t.failures
                 << " failures\n" << t.log);
    CHECK(t.failures == 0);
    // The cases must exercise the solver: a good share of the lines meet the sweep.
    if (requireHits) CHECK(t.hits >= t.cases / 4);
}

/// A point of `part`'s side at a height drawn within it, along `radial` from the axis at pose
/// (tip, axis), and the side's outward normal there from the radius's slope (a central difference).
void sidePoint(std::mt19937_64& rng, const oracle::Part& part, const Vec3& tip, const Vec3& axis, const Vec3& radial,
               Vec3& point, Vec3& normal) {
    constexpr double kStep = 1e-6;
    const double z = cases::uniform(rng, part.za + 2 * kStep, part.zb - 2 * kStep);
    const double slope = (part.radius(z + kStep) - part.radius(z - kStep)) / (2 * kStep);
    point = tip + z * axis + part.radius(z) * radial;
    normal = glm::normalize(radial - slope * axis);
}

/// A random case whose move turns 10^U(lowest, highest) degrees and travels 0.05 to 40 mm, or
/// not at all one time in `still`.
Case randomTurningCase(std::mt19937_64& rng, double lowest, double highest, unsigned still) {
    const double angle = degrees(std::pow(10.0, cases::uniform(rng, lowest, highest)));
    return randomCase(rng, randomMove(rng, angle, rng() % still == 0 ? 0.0 : cases::uniform(rng, 0.05, 40.0)));
}

/// A random pose of case `c`'s move, one of its tool's parts, and that part's bottom or top rim:
/// the rim's height z above the tip.
struct RimPoint {
    Vec3 tip{0.0}, axis{0.0};
    const oracle::Part* part = nullptr;
    bool bottom = false;
    double z = 0.0;
};
RimPoint rimPoint(const Case& c, std::mt19937_64& rng) {
    const SweepOracle o(c.model->parts, c.move);
    RimPoint r;
    o.pose(cases::uniform(rng, 0, 1), r.tip, r.axis);
    r.part = &c.model->parts[rng() % c.model->parts.size()];
    r.bottom = rng() % 2;
    r.z = r.bottom ? r.part->za : r.part->zb;
    return r;
}

/// Checks case `c` along a line through `point` that crosses the face with outward normal `normal`
/// there at 10 to 80 degrees from its tangent plane, with a tolerance of 1e-2 to 1e-4 mm: a coarse
/// tolerance lets note o (turning_linear_search.cpp) settle wide nodes, where its remainder is
/// largest.
void checkAcross(Case c, const Vec3& point, const Vec3& normal, Tally& tally, std::mt19937_64& rng) {
    const double elevation = degrees(cases::uniform(rng, 10, 80));
    const Vec3 dir = glm::normalize(std::cos(elevation) * cases::randomPerpendicular(rng, normal) +
                                    std::sin(elevation) * normal);
    c.line = Line{point - cases::uniform(rng, -30, 30) * dir, dir};
    c.epsilon = std::pow(10.0, -double(2 + rng() % 3));
    checkCase(c, tally, rng);
}
}  // namespace

// ---- The oracle against closed forms, without the solver --------------------------------------

namespace {

/// A signed offset from a surface: +-10^U(-9, -0.5) mm, so that points fall on both sides at every
/// scale from below kRounding to well clear.
double offset(std::mt19937_64& rng) {
    return (rng() % 2 ? 1.0 : -1.0) * std::pow(10.0, cases::uniform(rng, -9, -0.5));
}

/// Check that the oracle's certificates agree with a known signed distance `exact(x)` (> 0
/// outside S, < 0 inside by the depth in the deepest single pose) at points `near(rng)` around
/// the sweep's surface, and that they are sharp: a point clearly outside (or deep) gets its
/// certificate.
template <class Exact, class Near>
void selfCheck(const std::vector<oracle::Part>& parts, const Move& m, Exact&& exact, Near&& near,
               std::mt19937_64& rng, int points, int& unsound, int& missed, int& decided) {
    const SweepOracle o(parts, m);
    // The closed forms' own rounding, for coordinates below 100 mm.
    constexpr double kExactRounding = 1e-12;
    // Sharpness margins: a point this far outside must be certified (chord error, rounding and
    // the finest node's V w / 2 are all far below), and one this deep must get a witness (the
    // guide's grid and golden search find the deepest pose of these smooth cases to ~1e-6 mm).
    constexpr double kSharpOutside = 1e-5, kSharpDepth = 1e-4;
    constexpr double kDepth = 1e-4;
    for (int i = 0; i < points; ++i) {
        const Vec3 x = near(rng);
        const double e = exact(x);
        const bool outside = o.certainlyOutside(x);
        const bool deep = o.deepWitness(x, kDepth).has_value();
        decided += outside || deep;
        if ((outside && e < kRounding - kExactRounding) || (deep && -e < kDepth - kExactRounding)) ++unsound;
        if ((e > kSharpOutside && !outside) || (-e > kDepth + kSharpDepth && !deep)) ++missed;
    }
}

}  // namespace

TEST_CASE("turning oracle: certificates agree with closed forms (capsule, ball turning in place, plunge)",
          "[sweep][turning]") {
    std::mt19937_64 rng(20261123);
    int unsound = 0, missed = 0, decided = 0;
    const int points = scaled(2000);
    for (int trial = 0; trial < 6; ++trial) {
        const double r = cases::uniform(rng, 1.0, 8.0);
        // A sphere resting on the tip: centre r along the axis.
        const std::vector<oracle::Part> ball{
            models::part(0, 2 * r, [r](double z) { return models::capRadius(r, z); }, r)};

        // Fixed axis along a line: the capsule around the centre's segment.
        Move line = randomMove(rng, 0.0, cases::uniform(rng, 0, 30));
        line.startAxis = line.axis;
        const Vec3 c0 = line.start + r * line.axis, f = line.end - line.start;
        auto capsule = [&](const Vec3& x) {
            const double s = glm::dot(f, f) > 0 ? std::clamp(glm::dot(x - c0, f) / glm::dot(f, f), 0.0, 1.0) : 0.0;
            return glm::length(x - c0 - s * f) - r;
        };
        auto nearCapsule = [&](std::mt19937_64& g) {
            return c0 + cases::uniform(g, 0, 1) * f + (r + offset(g)) * cases::randomUnit(g);
        };
        selfCheck(ball, line, capsule, nearCapsule, rng, points, unsound, missed, decided);

        // Turning in place by up to 170 degrees: spheres centred on an arc of radius r.
        const Move turn = randomMove(rng, degrees(cases::uniform(rng, 1, 170)), 0.0);
        const Vec3 a0 = *turn.startAxis, a1 = turn.axis;
        const double theta = std::acos(std::clamp(glm::dot(a0, a1), -1.0, 1.0));
        const Vec3 b = glm::normalize(a1 - glm::dot(a0, a1) * a0);
        auto arc = [&](const Vec3& x) {
            const Vec3 d = x - turn.start;
            const double p = glm::dot(d, a0), q = glm::dot(d, b);
            const double off = glm::length(d - p * a0 - q * b);
            // The nearest point of the arc [0, theta] of the circle of radius r: at x's own
            // angle when the arc holds it, else at an end.
            double best = oracle::kInf;
            for (double t : {0.0, theta, std::clamp(std::atan2(q, p), 0.0, theta)})
                best = std::min(best, std::hypot(off, std::hypot(p - r * std::cos(t), q - r * std::sin(t))));
            return best - r;
        };
        auto nearArc = [&](std::mt19937_64& g) {
            const double t = cases::uniform(g, 0, theta);
            return turn.start + r * (a0 * std::cos(t) + b * std::sin(t)) + (r + offset(g)) * cases::randomUnit(g);
        };
        selfCheck(ball, turn, arc, nearArc, rng, points, unsound, missed, decided);

        // A flat end mill (a cylinder) plunging along its axis: a longer cylinder.
        const double rc = cases::uniform(rng, 0.5, 10.0), len = cases::uniform(rng, 5.0, 40.0);
        const std::vector<oracle::Part> flat{models::part(0, len, [rc](double) { return rc; }, rc)};
        Move plunge = randomMove(rng, 0.0, 0.0, true);
        const double travel = cases::uniform(rng, -20, 20);
        plunge.end = plunge.start + travel * plunge.axis;
        const double lo = std::min(0.0, travel), hi = std::max(0.0, travel) + len;
        auto cylinder = [&](const Vec3& x) {
            const Vec3 d = x - plunge.start;
            const double z = glm::dot(d, plunge.axis), rho = glm::length(glm::cross(d, plunge.axis));
            const double dz = std::max(lo - z, z - hi), dr = rho - rc;
            if (dz > 0 || dr > 0) return std::hypot(std::max(dz, 0.0), std::max(dr, 0.0));
            // Inside: the depth in the deepest single pose, whose bottom s in [lo, hi - len] is
            // nearest to centring the cylinder on the point.
            const double s = std::clamp(z - 0.5 * len, lo, hi - len);
            return -std::min({-dr, z - s, s + len - z});
        };
        auto nearCylinder = [&](std::mt19937_64& g) {
            // Near the side or near an end face. The side slides along itself, so a point just
            // outside it keeps its distance at every pose that covers its height, and check 1's
            // search needs about |f| / (2 d) nodes to settle it (e): outside the side, the points
            // keep a distance d >= kSideOffset.
            constexpr double kSideOffset = 1e-2;
            const Vec3 across = cases::randomPerpendicular(g, plunge.axis);
            if (g() % 2) {
                const double d = g() % 2 ? -std::abs(offset(g)) : cases::uniform(g, kSideOffset, 0.3);
                return plunge.start + cases::uniform(g, lo, hi) * plunge.axis + (rc + d) * across;
            }
            const double z = g() % 2 ? lo - offset(g) : hi + offset(g);
            return plunge.start + z * plunge.axis + cases::uniform(g, 0, rc) * across;
        };
        selfCheck(flat, plunge, cylinder, nearCylinder, rng, points, unsound, missed, decided);
    }
    INFO(unsound << " unsound certificates, " << missed << " points clearly outside or deep left uncertified, "
                 << decided << " decided");
    CHECK(unsound == 0);
    CHECK(missed == 0);
    // Most points are farther than the chord error from the surface and get decided.
    CHECK(decided >= 18 * points * 3 / 4);
}

TEST_CASE("turning oracle: certificates agree with the fixed-axis oracle (oracle.h) on every tool kind",
          "[sweep][turning]") {
    std::mt19937_64 rng(20261124);
    int unsound = 0, certified = 0;
    const int trials = scaled(200);
    for (int trial = 0; trial < trials; ++trial) {
        const auto kind = models::Kind(trial % int(models::Kind::Count));
        const models::Model model = models::make(kind, rng);
        const Move m = randomMove(rng, 0.0, rng() % 4 == 0 ? 0.0 : cases::uniform(rng, 0, 30), true);
        const SweepOracle o(model.parts, m);
        const oracle::Motion motion{m.start, m.end - m.start, m.axis};
        for (int i = 0; i < 20; ++i) {
            // Points near the surface of a random pose, where the two oracles are most at risk.
            const double u = cases::uniform(rng, 0, 1);
            const oracle::Part& part = model.parts[rng() % model.parts.size()];
            const double z = cases::uniform(rng, part.za - 0.5, part.zb + 0.5);
            const double rho = std::max(0.0, part.radius(std::clamp(z, part.za, part.zb)) + cases::uniform(rng, -0.05, 0.05));
            const Vec3 x = m.start + u * (m.end - m.start) + z * m.axis + rho * cases::randomPerpendicular(rng, m.axis);
            bool inside = false;
            for (const oracle::Part& p : model.parts)
                inside = inside || oracle::phi(p, motion, Line{x, m.axis}, 0.0) <= 0.0;
            const bool outside = o.certainlyOutside(x), deep = o.deepWitness(x, 1e-4).has_value();
            certified += outside || deep;
            if ((outside && inside) || (deep && !inside)) {
                ++unsound;
                INFO(models::name(kind) << " point " << cases::str(x) << " outside " << outside << " deep " << deep);
                CHECK(false);
            }
        }
    }
    CHECK(unsound == 0);
    // The points near the surface are mostly decided.
    CHECK(certified >= trials * 20 / 2);
}

// ---- The solver against the oracle -------------------------------------------------------------

TEST_CASE("turning sweep vs oracle: random tools, turns, moves and lines", "[sweep][turning]") {
    std::mt19937_64 rng(20261123);
    Tally tally;
    for (int i = 0, n = scaled(600); i < n; ++i) {
        double angle = 0.0;
        switch (rng() % 4) {
        case 0: angle = std::pow(10.0, cases::uniform(rng, -7, -1)); break;
        case 1: angle = degrees(cases::uniform(rng, 0, 10)); break;
        case 2: angle = degrees(cases::uniform(rng, 10, 90)); break;
        default: angle = degrees(cases::uniform(rng, 90, 178)); break;
        }
        const double travel = rng() % 5 == 0 ? 0.0 : cases::uniform(rng, 0, 40);
        checkCase(randomCase(rng, randomMove(rng, angle, travel)), tally, rng);
    }
    report(tally);
}

TEST_CASE("turning sweep vs oracle: turns from 0.001 to 90 degrees", "[sweep][turning]") {
    std::mt19937_64 rng(20261125);
    Tally tally;
    for (double angle : {0.001, 0.01, 0.1, 1.0, 5.0, 15.0, 30.0, 45.0, 60.0, 90.0})
        for (int i = 0, n = scaled(30); i < n; ++i)
            checkCase(randomCase(rng, randomMove(rng, degrees(angle), cases::uniform(rng, 0, 30))), tally, rng);
    report(tally);
    // Linear nodes search these moves, large turns too (turning.cpp, kLinearLevelsSaved); the
    // search of static poses is left to moves whose tip the machine carries, which
    // rotary_sweep_oracle_test.cpp checks.
    CHECK(tally.linear >= tally.cases / 4);
}

TEST_CASE("turning sweep vs oracle: a pure rotation about the tip", "[sweep][turning]") {
    // The rotation alone: a zero-length move that turns. Every other case keeps a travel of
    // 1e-13 to 1e-5 mm, either side of the length below which a node's fixed-axis sweep takes
    // its move as a static pose (tol::kZeroMove).
    std::mt19937_64 rng(20261126);
    Tally tally;
    for (int i = 0, n = scaled(150); i < n; ++i) {
        const double angle = degrees(cases::uniform(rng, 0.5, 150));
        const double travel = i % 2 ? std::pow(10.0, cases::uniform(rng, -13.0, -5.0)) : 0.0;
        checkCase(randomCase(rng, randomMove(rng, angle, travel)), tally, rng);
    }
    report(tally);
}

TEST_CASE("turning sweep vs oracle: short moves turning a little, as real programs' are", "[sweep][turning]") {
    // The median feed move of the LinuxCNC boat and impeller programs travels about 0.6 mm and
    // turns 0.2 to 0.6 degrees: there the search settles most nodes by their end poses' faces
    // (turning_linear_search.cpp, note j), whose bound is of second order in the node's width.
    std::mt19937_64 rng(20261201);
    Tally tally;
    for (int i = 0, n = scaled(300); i < n; ++i) {
        const double angle = degrees(std::pow(10.0, cases::uniform(rng, -1.5, 0.5)));
        checkCase(randomCase(rng, randomMove(rng, angle, cases::uniform(rng, 0.05, 2.0))), tally, rng);
    }
    report(tally);
    CHECK(tally.linear >= tally.cases / 2);
}

TEST_CASE("turning sweep vs oracle: tolerances of 1e-5 and 1e-6 mm", "[sweep][turning]") {
    // At a fine tolerance the linear nodes' leaves lie deep (level 23 for a flat D10 turning 30
    // degrees at 1e-6 mm), but the search near a graze stops where note j's bound meets the
    // tolerance (turning.cpp), about half as deep.
    std::mt19937_64 rng(20261202);
    Tally tally;
    for (int i = 0, n = scaled(150); i < n; ++i) {
        Case c = randomCase(rng, randomMove(rng, degrees(cases::uniform(rng, 0.1, 30)), cases::uniform(rng, 0, 40)));
        c.epsilon = rng() % 2 ? 1e-5 : kMinTurnTolerance;
        checkCase(c, tally, rng);
    }
    report(tally);
    CHECK(tally.linear >= tally.cases / 2);
}

TEST_CASE("turning sweep vs oracle: dexel lines through a rim, where the line's end may stop at a kink",
          "[sweep][turning]") {
    // A lattice line through a point on a part's bottom or top rim at some pose, or within
    // 1e-6 to 0.1 mm of it, meets the envelope near where that rim sweeps it: where the rim makes
    // the line's end, the search looks for the pose at which the line passes through the rim
    // (turning_linear_search.cpp, note k).
    std::mt19937_64 rng(20261203);
    Tally tally;
    for (int i = 0, n = scaled(300); i < n; ++i) {
        const double angle = degrees(std::pow(10.0, cases::uniform(rng, -1.5, 1.5)));
        Case c = randomCase(rng, randomMove(rng, angle, cases::uniform(rng, 0.05, 40.0)), true);
        const RimPoint r = rimPoint(c, rng);
        const double near = (rng() % 2 ? 1.0 : -1.0) * std::pow(10.0, cases::uniform(rng, -6, -1));
        const Vec3 point = r.tip + r.z * r.axis + (r.part->radius(r.z) + near) * cases::randomPerpendicular(rng, r.axis);
        c.line = Line{point - cases::uniform(rng, -30, 30) * c.line.dir, c.line.dir};
        checkCase(c, tally, rng);
    }
    report(tally);
    CHECK(tally.linear >= tally.cases / 2);
}

TEST_CASE("turning sweep vs oracle: lines through a rim exactly at the move's first or last pose",
          "[sweep][turning]") {
    // With the tip at the origin and the axis along z at the first (or last) pose, a line through
    // a point of the bottom rim there meets it exactly at a node's end: the rim's pose search
    // (turning_linear_search.cpp, note k) starts from a bracket with a zero at one end, and its
    // pose must stay inside the node (a review found one 0.015 mm past the end of the move).
    std::mt19937_64 rng(20261130);
    Tally tally;
    const double d = 10.0, r = d / 2;
    const ToolLengths lengths{25.0, 40.0};
    const Vec3 rims[] = {{r, 0, 0}, {0, r, 0}, {-r, 0, 0}, {0, -r, 0}};
    const Vec3 travels[] = {{30, 0, 5}, {0, 30, -5}, {20, 10, 3}, {-15, 5, 0}};
    for (int i = 0; i < scaled(96); ++i) {
        Case c;
        c.kind = models::Kind::Flat;
        c.model.emplace(models::Model{flatEndMill(d, lengths), {models::part(0, lengths.total, [r](double) { return r; }, r)}});
        const Vec3 tilted = glm::normalize(Vec3(cases::uniform(rng, -0.2, 0.2), cases::uniform(rng, -0.2, 0.2), 1.0));
        const Vec3 travel = travels[i % 4];
        if (i % 8 < 4) {  // the rim at the first pose
            c.move.start = Vec3(0.0), c.move.end = travel, c.move.startAxis = Vec3(0, 0, 1), c.move.axis = tilted;
        } else {  // at the last
            c.move.start = -travel, c.move.end = Vec3(0.0), c.move.startAxis = tilted, c.move.axis = Vec3(0, 0, 1);
        }
        // Through the rim point itself, so that it lies on the line to the last bit.
        const Vec3 dir = i % 3 == 0 ? glm::normalize(Vec3(0.6, 0.0, 0.8)) : cases::randomUnit(rng);
        c.line = Line{rims[(i / 8) % 4], dir};
        checkCase(c, tally, rng);
    }
    report(tally);
}

TEST_CASE("turning sweep vs oracle: a long cutter's bands, where a line's care reaches few of them",
          "[sweep][turning]") {
    // A flat end 50 mm long, searched in eight bands (turning.cpp, note i), on moves of 10 to 40 mm
    // turning 0.5 to 30 degrees. Dexel lines through a point within 8 mm of its tip at some pose,
    // asked about a stretch of 0.5 to 6 mm about that point, as the cutting loop asks about a
    // dexel's material: the bands whose heights that stretch never takes are not searched
    // (turning_linear_search.cpp, note p), and check 2 holds inside the stretch.
    std::mt19937_64 rng(20261130);
    Tally tally;
    int banded = 0;
    for (int i = 0, n = scaled(300); i < n; ++i) {
        const double angle = degrees(std::pow(10.0, cases::uniform(rng, -0.3, 1.5)));
        Case c;
        c.model.emplace(models::Model{flatEndMill(10.0, {50.0, 50.0}), {models::part(0, 50.0, [](double) { return 5.0; }, 5.0)}});
        c.move = randomMove(rng, angle, cases::uniform(rng, 10.0, 40.0));
        c.epsilon = std::pow(10.0, -double(3 + rng() % 3));
        const SweepOracle o(c.model->parts, c.move);
        Vec3 tip, axis;
        o.pose(cases::uniform(rng, 0, 1), tip, axis);
        const Vec3 point = tip + cases::uniform(rng, -1.0, 8.0) * axis +
                           cases::uniform(rng, 0.0, 6.0) * cases::randomPerpendicular(rng, axis);
        Vec3 dir(0.0);
        dir[int(rng() % 3)] = rng() % 2 ? 1.0 : -1.0;
        const double back = cases::uniform(rng, -30, 30), half = cases::uniform(rng, 0.25, 3.0);
        c.line = Line{point - back * dir, dir};
        banded += TurningSweep(c.model->tool, c.move, c.epsilon).linearBands() > 1;
        checkCase(c, tally, rng, {Interval{back - half, back + half}});
    }
    report(tally);
    CHECK(banded >= tally.cases / 2);
}

TEST_CASE("turning sweep vs oracle: lines a part first or last meets at a rim, clipping its corner",
          "[sweep][turning]") {
    // A line through a point of a part's bottom or top rim at some pose, entering one face
    // there and leaving the other at once, so that the pose only touches it: the line is first
    // or last met at the rim, near where one end pose's part misses it (turning_linear_search.cpp,
    // note k), and its interval at that pose is next to nothing, so the poses between it and the
    // next are bridged (note q). Asked, half the time, about a stretch of 0.5 to 6 mm about the
    // point, as the cutting loop asks about a dexel's material.
    std::mt19937_64 rng(20261201);
    Tally tally;
    for (int i = 0, n = scaled(400); i < n; ++i) {
        const double angle = degrees(std::pow(10.0, cases::uniform(rng, -1.0, 1.5)));
        Case c = randomCase(rng, randomMove(rng, angle, cases::uniform(rng, 0.5, 40.0)));
        const RimPoint r = rimPoint(c, rng);
        const Vec3 radial = cases::randomPerpendicular(rng, r.axis);
        const Vec3 point = r.tip + r.z * r.axis + r.part->radius(r.z) * radial;
        // Into the disk face and out of the side: along the axis towards the part and out along
        // the radial, with a random share across both.
        const Vec3 across = glm::cross(r.axis, radial);
        const Vec3 dir = glm::normalize(cases::uniform(rng, 0.1, 1.0) * (r.bottom ? r.axis : -r.axis) +
                                        cases::uniform(rng, 0.1, 1.0) * radial + cases::uniform(rng, -1.0, 1.0) * across);
        const double back = cases::uniform(rng, -30, 30), half = cases::uniform(rng, 0.25, 3.0);
        c.line = Line{point - back * dir, dir};
        checkCase(c, tally, rng, rng() % 2 ? std::vector<Interval>{} : std::vector<Interval>{{back - half, back + half}});
    }
    report(tally);
    CHECK(tally.linear >= tally.cases / 2);
}

TEST_CASE("turning sweep vs oracle: lines nearly along a face of a pose, while the axis turns fast",
          "[sweep][turning]") {
    // A line through a point on a part's side, bottom or top at the first, last or some middle
    // pose, within 1e-6 to 0.1 rad of that face's tangent plane. There the face's normal is nearly
    // across the line, so as the axis turns the face soon tilts to take in points of the line far
    // from its crossing: the stretch by which a crossing bounds the line
    // (turning_linear_search.cpp, notes j and m) must stop where the turn can tilt the face past
    // the line, |n.d| / omega.
    std::mt19937_64 rng(20261129);
    Tally tally;
    for (int i = 0, n = scaled(300); i < n; ++i) {
        Case c = randomTurningCase(rng, -0.5, 2.0, 3);
        const SweepOracle o(c.model->parts, c.move);
        const double poses[] = {0.0, 1.0, cases::uniform(rng, 0, 1)};
        Vec3 tip, axis;
        o.pose(poses[rng() % 3], tip, axis);
        const oracle::Part& part = c.model->parts[rng() % c.model->parts.size()];
        const Vec3 radial = cases::randomPerpendicular(rng, axis);
        Vec3 point, normal;
        switch (rng() % 3) {
        case 0:  // the side
            sidePoint(rng, part, tip, axis, radial, point, normal);
            break;
        case 1:  // the bottom
            point = tip + part.za * axis + cases::uniform(rng, 0, 1) * part.radius(part.za) * radial;
            normal = -axis;
            break;
        default:  // the top
            point = tip + part.zb * axis + cases::uniform(rng, 0, 1) * part.radius(part.zb) * radial;
            normal = axis;
            break;
        }
        const double tilt = (rng() % 2 ? 1.0 : -1.0) * std::pow(10.0, cases::uniform(rng, -6, -1));
        const Vec3 dir = glm::normalize(cases::randomPerpendicular(rng, normal) + tilt * normal);
        c.line = Line{point - cases::uniform(rng, -30, 30) * dir, dir};
        checkCase(c, tally, rng);
    }
    report(tally);
    CHECK(tally.linear >= tally.cases / 2);
}

TEST_CASE("turning sweep vs oracle: lines through a disk face, whose end may dip past both end poses'",
          "[sweep][turning]") {
    // A line through a point of a part's bottom or top disk at a middle pose u*, crossing it at 10
    // to 80 degrees from the disk's plane, with a tolerance of 1e-2 to 1e-4 mm. As the tool moves
    // and turns, the disk's plane crosses the line farther out at poses between a node's ends than
    // at either: the plane bounds those points by its values at three poses and a third-order
    // remainder (turning_linear_search.cpp, note o). Most points are taken where the plane stops
    // moving along its normal at u*, a'.(z - p) = a.f (a' by a central difference of the oracle's
    // poses), so that the line's end dips deepest near u*.
    std::mt19937_64 rng(20261130);
    Tally tally;
    for (int i = 0, n = scaled(300); i < n; ++i) {
        Case c = randomTurningCase(rng, 0.0, 1.95, 4);
        const SweepOracle o(c.model->parts, c.move);
        const double at = cases::uniform(rng, 0.1, 0.9);
        constexpr double kStep = 1e-6;
        Vec3 tip, axis, before, after, unused;
        o.pose(at, tip, axis);
        o.pose(at - kStep, unused, before);
        o.pose(at + kStep, unused, after);
        const Vec3 turn = (after - before) / (2 * kStep);
        const oracle::Part& part = c.model->parts[rng() % c.model->parts.size()];
        const bool bottom = rng() % 2 == 0;
        const double z = bottom ? part.za : part.zb;
        const Vec3 normal = bottom ? -axis : axis;
        const double still = glm::dot(axis, c.move.end - c.move.start) / glm::length(turn);
        const Vec3 point = rng() % 4 != 0 && std::abs(still) < 0.95 * part.radius(z)
                               ? tip + z * axis + still * glm::normalize(turn)
                               : tip + z * axis + cases::uniform(rng, 0, 0.95) * part.radius(z) *
                                                      cases::randomPerpendicular(rng, axis);
        checkAcross(c, point, normal, tally, rng);
    }
    report(tally);
    CHECK(tally.linear >= tally.cases / 2);
}

TEST_CASE("turning sweep vs oracle: lines across a part's side, whose end may dip past both end poses'",
          "[sweep][turning]") {
    // A line through a point of a part's side at a middle pose, crossing it at 10 to 80 degrees
    // from its tangent plane, with a tolerance of 1e-2 to 1e-4 mm. Where the side is a cylinder,
    // the distance from its axis bounds the line's points beyond by three poses and a third-order
    // remainder (turning_linear_search.cpp, note o), while the line runs away from the axis.
    std::mt19937_64 rng(20261131);
    Tally tally;
    for (int i = 0, n = scaled(300); i < n; ++i) {
        Case c = randomTurningCase(rng, -1.0, 1.95, 4);
        const SweepOracle o(c.model->parts, c.move);
        Vec3 tip, axis;
        o.pose(cases::uniform(rng, 0.1, 0.9), tip, axis);
        const oracle::Part& part = c.model->parts[rng() % c.model->parts.size()];
        Vec3 point, normal;
        sidePoint(rng, part, tip, axis, cases::randomPerpendicular(rng, axis), point, normal);
        checkAcross(c, point, normal, tally, rng);
    }
    report(tally);
    CHECK(tally.linear >= tally.cases / 2);
}

TEST_CASE("turning sweep vs oracle: the axis turning through a lattice direction", "[sweep][turning]") {
    std::mt19937_64 rng(20261127);
    Tally tally;
    for (int i = 0, n = scaled(150); i < n; ++i) {
        // From (sin a, 0, cos a) through +z to (-sin b, 0, cos b), its coordinates permuted so
        // that the turn passes through +x, +y or +z; with dexel lines most of the time.
        const double a = degrees(cases::uniform(rng, 0.001, 60)), b = degrees(cases::uniform(rng, 0.001, 60));
        const int shift = int(rng() % 3);
        auto lattice = [&](const Vec3& v) { return Vec3(v[(0 + shift) % 3], v[(1 + shift) % 3], v[(2 + shift) % 3]); };
        Move m = randomMove(rng, 0.0, rng() % 3 == 0 ? 0.0 : cases::uniform(rng, 0, 30));
        m.startAxis = lattice(Vec3(std::sin(a), 0, std::cos(a)));
        m.axis = lattice(Vec3(-std::sin(b), 0, std::cos(b)));
        checkCase(randomCase(rng, m, rng() % 4 != 0), tally, rng);
    }
    report(tally);
}

TEST_CASE("turning sweep vs oracle: the tip moving along the axis", "[sweep][turning]") {
    std::mt19937_64 rng(20261128);
    Tally tally;
    for (int i = 0, n = scaled(150); i < n; ++i) {
        Move m = randomMove(rng, degrees(cases::uniform(rng, 0.01, 90)), 0.0);
        // Along the end axis, the start axis or the middle one, either way.
        const Vec3 middle = glm::normalize(*m.startAxis + m.axis);
        const Vec3 along[] = {m.axis, *m.startAxis, middle};
        m.end = m.start + cases::uniform(rng, -30, 30) * along[rng() % 3];
        checkCase(randomCase(rng, m), tally, rng);
    }
    report(tally);
}

TEST_CASE("turning sweep vs oracle: nearly antipodal axes; opposite axes are refused", "[sweep][turning]") {
    std::mt19937_64 rng(20261129);
    Tally tally;
    // Down to 1e-5 degrees short of opposite, where a0 x a1 is still 1.7e-7 long, far above the
    // kParallel that the refusal below needs.
    for (double angle : {170.0, 179.0, 179.9, 179.99, 179.99999})
        for (int i = 0, n = scaled(30); i < n; ++i)
            checkCase(randomCase(rng, randomMove(rng, degrees(angle), rng() % 2 ? 0.0 : cases::uniform(rng, 0, 30))),
                      tally, rng);
    report(tally);

    const models::Model model = models::make(models::Kind::Ball, rng);
    Move m = randomMove(rng, 0.0, 10.0);
    m.startAxis = -m.axis;
    CHECK_THROWS_WITH(TurningSweep(model.tool, m), Catch::Matchers::Contains("opposite"));
    m.axis = Vec3(0, 0, 1);
    m.startAxis = Vec3(0, 0, -1);
    CHECK_THROWS_WITH(TurningSweep(model.tool, m), Catch::Matchers::Contains("opposite"));
    // Within kParallel of opposite, no one great circle either.
    m.startAxis = glm::normalize(Vec3(0, 1e-13, -1));
    CHECK_THROWS_WITH(TurningSweep(model.tool, m), Catch::Matchers::Contains("opposite"));
}

TEST_CASE("turning sweep vs oracle: a fixed axis (no start axis)", "[sweep][turning]") {
    std::mt19937_64 rng(20261130);
    Tally tally;
    for (int i = 0, n = scaled(150); i < n; ++i)
        checkCase(randomCase(rng, randomMove(rng, 0.0, rng() % 5 == 0 ? 0.0 : cases::uniform(rng, 0, 40), true)), tally,
                  rng);
    report(tally);
}

TEST_CASE("turning sweep vs oracle: ball ends swept as capsules, and those searched whole", "[sweep][turning]") {
    std::mt19937_64 rng(20261124);
    Tally tally;
    struct Variant {
        double d, total, angle, epsilon;
        bool bull;
        std::size_t balls;
        const char* what;
    };
    const Variant variants[] = {
        {4.0, 40.0, 5.0, 1e-4, false, 1, "the impeller's ball end turning 5 degrees"},
        {10.0, 15.0, 60.0, 1e-4, false, 1, "turning 60 degrees"},
        {6.0, 12.0, 20.0, 1e-4, true, 1, "a bull nose whose corner radius is half its diameter"},
        {10.0, 7.0, 30.0, 1e-4, false, 0, "a cylinder shorter than the radius: the ball is not inside the tool"},
        {40.0, 45.0, 90.0, 1e-5, false, 0, "a turn that needs more than 256 chords"},
        {3e-4, 1.0, 30.0, 1e-4, false, 0, "a radius below twice the tolerance"},
    };
    for (const Variant& v : variants) {
        const double r = v.d / 2;
        const ToolLengths lengths{v.total, v.total};
        const models::Model model{v.bull ? bullNoseEndMill(v.d, r, lengths) : ballEndMill(v.d, lengths),
                                  {models::part(0, v.total, [r](double z) { return z < r ? models::capRadius(r, z) : r; }, r)}};
        for (int i = 0, n = scaled(40); i < n; ++i) {
            Case c;
            c.kind = v.bull ? models::Kind::Bull : models::Kind::Ball;
            c.model.emplace(model);
            c.move = randomMove(rng, degrees(v.angle), rng() % 4 == 0 ? 0.0 : cases::uniform(rng, 0, 30));
            c.line = randomLine(rng, model, c.move, rng() % 2 == 0);
            c.epsilon = v.epsilon;
            INFO(v.what);
            CHECK(TurningSweep(model.tool, c.move, c.epsilon).capsuleBalls() == v.balls);
            checkCase(c, tally, rng);
        }
    }
    report(tally);
}

TEST_CASE("turning sweep vs oracle: a line the tool cannot reach gets nothing", "[sweep][turning]") {
    std::mt19937_64 rng(20261131);
    Tally tally;
    for (int i = 0, n = scaled(150); i < n; ++i) {
        Case c = randomCase(rng, randomMove(rng, degrees(cases::uniform(rng, 0, 120)), cases::uniform(rng, 0, 40)));
        // The line passes (|f| / 2 + reach + gap) from the middle of the tip's segment, so at
        // least `gap` from every tool point at every pose.
        constexpr double kGap = 0.01;
        const SweepOracle o(c.model->parts, c.move);
        const Vec3 mid = 0.5 * (c.move.start + c.move.end);
        const double away = 0.5 * glm::length(c.move.end - c.move.start) + o.reach() + kGap;
        c.line.origin = mid + away * cases::randomPerpendicular(rng, c.line.dir) + cases::uniform(rng, -30, 30) * c.line.dir;
        const std::vector<Interval> out = checkCase(c, tally, rng);
        INFO(describe(c));
        CHECK(out.empty());
    }
    report(tally, false);
}
