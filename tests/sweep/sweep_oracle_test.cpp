// The sweep solver against the brute-force oracle (oracle.h): random tools of every kind, random
// tool axes, moves and dexel directions, one test case per degenerate family of method.md
// section 5. Fixed seeds; case counts scale with DEXELMILL_TEST_SCALE (default 1: 133,000 cases).
//
// Agreement: every removed interval longer than 2 kTolerance has a partner on the other side with
// both ends within kTolerance = 1e-6 mm; a stretch they disagree on beyond that must lie within
// kTangentDepth = 1e-9 mm of the sweep's boundary (a line grazing it, where rounding decides). The oracle's own error is far below that: its inner
// golden section leaves u within 4e-11 of the optimum (an error in Phi of about |f| 4e-11 mm,
// < 4e-9 mm for the moves here) and its bisections leave v within 2^-60 of the range, so a
// disagreement above 1e-6 mm needs a line crossing the boundary at a grazing angle below ~1e-3.
#include <catch2/catch.hpp>

#include <cstdint>
#include <random>
#include <sstream>

#include "dexelmill/sweep/sweep.h"
#include "oracle.h"
#include "oracle_cases.h"
#include "tool_models.h"

using namespace dexelmill;
using namespace cases;

namespace {

constexpr double kTolerance = 1e-6;

/// Where the line runs within this distance of the sweep's boundary (a tangent line, or one in a
/// plane that touches the tool along a circle), whether a stretch of it is inside is decided by
/// rounding: a stretch of length l along a surface of radius r is l^2 / (8 r) deep, 1e-13 mm for
/// l = 2e-6 mm at r = 5 mm. Such a stretch, disputed by the solver and the oracle, is accepted
/// when moving its middle by this distance (along the tool axis or across it) changes the oracle's
/// answer there.
constexpr double kTangentDepth = 1e-9;

/// Every interval of `a` longer than 2 tol has one in `b` with both ends within tol. Where not,
/// each stretch the two disagree on must lie within kTangentDepth of the boundary:
/// `nearBoundary(v)` says whether the line point at v does.
template <class NearBoundary>
bool covered(const std::vector<Interval>& a, const std::vector<Interval>& b, NearBoundary&& nearBoundary) {
    for (const Interval& x : a) {
        if (x.length() <= 2 * kTolerance) continue;
        bool found = false;
        for (const Interval& y : b)
            found = found || (std::abs(x.lo - y.lo) <= kTolerance && std::abs(x.hi - y.hi) <= kTolerance);
        if (found) continue;
        const Interval* partner = nullptr;
        for (const Interval& y : b)
            if (y.lo < x.hi && x.lo < y.hi) partner = &y;
        if (!partner) {
            if (!nearBoundary(0.5 * (x.lo + x.hi))) return false;
            continue;
        }
        if (std::abs(x.lo - partner->lo) > kTolerance && !nearBoundary(0.5 * (x.lo + partner->lo))) return false;
        if (std::abs(x.hi - partner->hi) > kTolerance && !nearBoundary(0.5 * (x.hi + partner->hi))) return false;
    }
    return true;
}

struct FamilyResult {
    int cases = 0, hits = 0, failures = 0;
    std::string firstFailures;
};

FamilyResult runFamily(Family family, std::uint64_t seed, int count) {
    std::mt19937_64 rng(seed);
    FamilyResult res;
    for (int i = 0; i < count; ++i) {
        const Case c = makeCase(family, rng);
        const Tool& tool = c.tool();
        const std::vector<oracle::Part>& parts = c.parts;
        const Vec3 &ps = c.ps, &f = c.f, &n = c.n;
        const Line& line = c.line;

        const MoveSweep sweep(tool, ps, ps + f, n);
        Interval solverParts[MoveSweep::kMaxParts];
        const std::size_t np = sweep.intersectParts(line, solverParts);
        std::vector<Interval> solver(solverParts, solverParts + np);

        const oracle::Motion motion{ps, f, n};
        std::vector<Interval> truth;
        for (std::size_t k = 0; k < parts.size(); ++k) {
            double hint = oracle::kInf;
            if (np == parts.size() && !solverParts[k].isEmpty())
                hint = 0.5 * (solverParts[k].lo + solverParts[k].hi);
            truth.push_back(oracle::removed(parts[k], motion, line, hint));
        }
        const std::vector<Interval> s = oracle::unite(solver, kTolerance, 0.0);
        const std::vector<Interval> t = oracle::unite(truth, kTolerance, 0.0);
        ++res.cases;
        if (!t.empty()) ++res.hits;
        auto insideAt = [&](const Vec3& p) {
            for (const oracle::Part& part : parts)
                if (oracle::phi(part, motion, Line{p, line.dir}, 0.0) <= 0.0) return true;
            return false;
        };
        auto nearBoundary = [&](double v) {
            const Vec3 p = line.origin + v * line.dir;
            const Vec3 across = glm::normalize(glm::cross(n, std::abs(n.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0)));
            const Vec3 across2 = glm::cross(n, across);
            const bool here = insideAt(p);
            for (const Vec3& dir : {n, -n, across, -across, across2, -across2})
                if (insideAt(p + kTangentDepth * dir) != here) return true;
            return false;
        };
        if (!(covered(s, t, nearBoundary) && covered(t, s, nearBoundary))) {
            if (++res.failures <= 5) {
                std::ostringstream m;
                m << "case " << i << ": " << describe(c) << "\n   solver " << str(s) << "\n   oracle " << str(t) << "\n";
                res.firstFailures += m.str();
            }
        }
    }
    return res;
}

void check(Family family, std::uint64_t seed, int baseCount) {
    const int count = std::max(1, int(baseCount * oracle::testScale()));
    const FamilyResult r = runFamily(family, seed, count);
    INFO(r.cases << " cases, " << r.hits << " hit the sweep, " << r.failures << " disagree\n" << r.firstFailures);
    CHECK(r.failures == 0);
    // The cases must exercise the solver: a good share of lines meet the sweep.
    CHECK(r.hits >= r.cases / 4);
}

}  // namespace

TEST_CASE("sweep vs oracle: general moves, any axis, any dexel direction", "[sweep][oracle]") {
    check(Family::General, 101, 30000);
}

TEST_CASE("sweep vs oracle: 3-axis moves with x, y, z dexels", "[sweep][oracle]") {
    check(Family::ThreeAxis, 102, 20000);
}

TEST_CASE("sweep vs oracle: horizontal moves (n.f = 0)", "[sweep][oracle]") {
    check(Family::Horizontal, 103, 10000);
}

TEST_CASE("sweep vs oracle: plunges and retracts (f parallel to n)", "[sweep][oracle]") {
    check(Family::Plunge, 104, 8000);
}

TEST_CASE("sweep vs oracle: zero-length moves", "[sweep][oracle]") {
    check(Family::ZeroLength, 105, 5000);
}

TEST_CASE("sweep vs oracle: dexel parallel to the move (w x f = 0)", "[sweep][oracle]") {
    check(Family::DexelAlongMove, 106, 6000);
}

TEST_CASE("sweep vs oracle: dexel parallel to the tool axis", "[sweep][oracle]") {
    check(Family::DexelAlongAxis, 107, 8000);
}

TEST_CASE("sweep vs oracle: nearly degenerate moves and dexels", "[sweep][oracle]") {
    check(Family::NearDegenerate, 108, 12000);
}

TEST_CASE("sweep vs oracle: tiny moves across the axis, nearly horizontal", "[sweep][oracle]") {
    check(Family::TinyAcross, 112, 10000);
}

TEST_CASE("sweep vs oracle: dexel lying in a flat face's plane", "[sweep][oracle]") {
    check(Family::DexelInFace, 109, 6000);
}

TEST_CASE("sweep vs oracle: cutting region and shank region", "[sweep][oracle]") {
    check(Family::Regions, 110, 10000);
}

TEST_CASE("sweep vs oracle: line in the move's plane of symmetry", "[sweep][oracle]") {
    check(Family::SymmetryPlane, 111, 8000);
}
