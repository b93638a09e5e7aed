// The sweep solver against the brute-force oracle (oracle.h): random tools of every kind, random
// tool axes, moves and dexel directions, one test case per degenerate family of method.md
// section 5. Fixed seeds; case counts scale with DEXELMILL_TEST_SCALE (default 1: 123,000 cases).
//
// Agreement: every removed interval longer than 2 kTolerance has a partner on the other side with
// both ends within kTolerance = 1e-6 mm; a stretch they disagree on beyond that must lie within
// kTangentDepth = 1e-9 mm of the sweep's boundary (a line grazing it, where rounding decides). The oracle's own error is far below that: its inner
// golden section leaves u within 4e-11 of the optimum (an error in Phi of about |f| 4e-11 mm,
// < 4e-9 mm for the moves here) and its bisections leave v within 2^-60 of the range, so a
// disagreement above 1e-6 mm needs a line crossing the boundary at a grazing angle below ~1e-3.
#include <catch2/catch.hpp>

#include <cstdint>
#include <iomanip>
#include <optional>
#include <random>
#include <sstream>

#include "dexelmill/sweep/sweep.h"
#include "oracle.h"
#include "tool_models.h"

using namespace dexelmill;

namespace {

constexpr double kTolerance = 1e-6;

enum class Family {
    General,         ///< any tool axis, any feed, any dexel direction
    ThreeAxis,       ///< axis +z, dexels along x, y, z (the tri-dexel stock's case)
    Horizontal,      ///< n . f = 0
    Plunge,          ///< f parallel to n, both senses
    ZeroLength,      ///< f = 0 (and |f| below the zero-move tolerance)
    DexelAlongMove,  ///< w x f = 0
    DexelAlongAxis,  ///< w parallel to the tool axis
    NearDegenerate,  ///< within 1e-14 .. 1e-3 rad of each of the above; tiny moves
    DexelInFace,     ///< horizontal move, the line lying in the bottom or top face's plane
    Regions,         ///< the cutting part [0, Lc] and the shank [Lc, L] swept separately
    SymmetryPlane    ///< axis z, a move along x or y, the line in the plane of the axis and feed
};

Vec3 randomUnit(std::mt19937_64& rng) {
    std::normal_distribution<double> g;
    Vec3 v;
    do v = Vec3(g(rng), g(rng), g(rng));
    while (glm::length(v) < 1e-3);
    return glm::normalize(v);
}

/// A unit vector perpendicular to n.
Vec3 randomPerpendicular(std::mt19937_64& rng, const Vec3& n) {
    Vec3 v;
    do {
        v = randomUnit(rng);
        v -= glm::dot(v, n) * n;
    } while (glm::length(v) < 1e-3);
    return glm::normalize(v);
}

double uniform(std::mt19937_64& rng, double a, double b) { return models::uniform(rng, a, b); }

std::string str(const Vec3& v) {
    std::ostringstream s;
    s << std::setprecision(17) << "(" << v.x << ", " << v.y << ", " << v.z << ")";
    return s.str();
}

std::string str(const Tool& tool) {
    std::ostringstream s;
    s << std::setprecision(17) << "Tool(\"" << tool.description() << "\", {";
    for (const ProfilePiece& p : tool.pieces()) {
        if (const auto* c = std::get_if<ConePiece>(&p))
            s << "ConePiece{" << c->z0 << ", " << c->z1 << ", " << c->r0 << ", " << c->r1 << "}, ";
        else if (const auto* a = std::get_if<ArcPiece>(&p))
            s << "ArcPiece{" << a->z0 << ", " << a->z1 << ", " << a->rc << ", " << a->zc << ", " << a->rho << "}, ";
    }
    s << "}, " << tool.cuttingLength() << ")";
    return s.str();
}

std::string str(const std::vector<Interval>& ivs) {
    std::ostringstream s;
    s << std::setprecision(17) << "{";
    for (const Interval& i : ivs) s << " [" << i.lo << ", " << i.hi << "]";
    return s.str() + " }";
}

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
    const int kinds = int(models::Kind::Count);
    for (int i = 0; i < count; ++i) {
        models::Kind kind = models::Kind(rng() % kinds);
        if (family == Family::DexelInFace && kind == models::Kind::NonConvex) kind = models::Kind::Flat;
        models::Model model = models::make(kind, rng);
        const Tool* tool = &model.tool;
        std::vector<oracle::Part> parts = model.parts;
        std::optional<Tool> region;
        if (family == Family::Regions) {
            const double lc = model.tool.cuttingLength(), total = model.tool.totalLength();
            const bool shank = lc < total - 1e-6 && rng() % 2;
            const double z0 = shank ? lc : 0.0, z1 = shank ? total : lc;
            region.emplace(model.tool.region(z0, z1));
            tool = &*region;
            parts = models::clip(model.parts, z0, z1);
        }
        const double length = parts.back().zb;
        double rBound = 0.0;
        for (const oracle::Part& p : parts) rBound = std::max(rBound, p.rBound);

        // The move.
        Vec3 n = (family == Family::ThreeAxis || family == Family::DexelInFace ||
                  family == Family::SymmetryPlane || rng() % 4 == 0)
                     ? Vec3(0, 0, 1)
                     : randomUnit(rng);
        Vec3 ps(uniform(rng, -10, 10), uniform(rng, -10, 10), uniform(rng, -10, 10));
        double len = rng() % 10 == 0 ? uniform(rng, 1e-3, 0.5) : uniform(rng, 0.5, 40.0);
        Vec3 f = len * randomUnit(rng);
        Vec3 w = randomUnit(rng);
        switch (family) {
        case Family::General:
        case Family::Regions:
            break;
        case Family::ThreeAxis: {
            const int m = int(rng() % 6);
            if (m == 0) f = Vec3(0, 0, rng() % 2 ? len : -len);
            else if (m <= 2) f.z = 0.0;
            w = Vec3(0.0);
            w[int(rng() % 3)] = 1.0;
            break;
        }
        case Family::Horizontal:
            f = len * randomPerpendicular(rng, n);
            if (n == Vec3(0, 0, 1)) f.z = 0.0;
            break;
        case Family::Plunge:
            f = (rng() % 2 ? len : -len) * n;
            break;
        case Family::ZeroLength:
            f = rng() % 2 ? Vec3(0.0) : 1e-10 * randomUnit(rng);
            break;
        case Family::DexelAlongMove:
            w = (rng() % 2 ? 1.0 : -1.0) * glm::normalize(f);
            break;
        case Family::DexelAlongAxis:
            w = rng() % 2 ? n : -n;
            break;
        case Family::NearDegenerate: {
            // Angles from 1e-14 to 1e-3 rad straddle the solver's switches (horizontal below 1e-12,
            // parallel to the feed below 1e-9); one move in four is 1e-9 to 1e-3 mm long, across
            // the zero-length switch.
            const double eps = std::pow(10.0, uniform(rng, -14.0, -3.0));
            if (rng() % 4 == 0) f = std::pow(10.0, uniform(rng, -9.0, -3.0)) * glm::normalize(f);
            const Vec3 perp = randomPerpendicular(rng, n);
            switch (rng() % 4) {
            case 0:  // nearly horizontal
                f = len * glm::normalize(perp + (rng() % 2 ? eps : -eps) * n);
                break;
            case 1:  // nearly a plunge
                f = (rng() % 2 ? len : -len) * glm::normalize(n + eps * perp);
                break;
            case 2:  // dexel nearly along the move
                w = glm::normalize(glm::normalize(f) + eps * randomPerpendicular(rng, glm::normalize(f)));
                break;
            default:  // dexel nearly along the axis
                w = glm::normalize(n + eps * perp);
                break;
            }
            break;
        }
        case Family::SymmetryPlane: {
            // Exact coordinates, so that the line lies exactly in the move's plane of symmetry.
            const int along = int(rng() % 2);
            f = Vec3(0.0);
            f[along] = std::round(uniform(rng, -30, 30));
            f.z = rng() % 3 == 0 ? 0.0 : std::round(uniform(rng, -10, 10));
            if (f == Vec3(0.0)) f.z = 1.0;
            w = Vec3(0.0);
            const double a = uniform(rng, 0.0, 2 * models::kPi);
            w[along] = std::cos(a), w.z = std::sin(a);
            if (rng() % 3 == 0) w = Vec3(0, 0, 1);
            break;
        }
        case Family::DexelInFace:
            // The tip at height 0 so that the face heights below are exact sums.
            ps = Vec3(std::round(ps.x), std::round(ps.y), 0.0);
            f.z = 0.0;
            w = rng() % 2 ? Vec3(double(rng() % 2), 0.0, 0.0) : randomUnit(rng);
            w.z = 0.0;
            if (glm::length(w) < 1e-3) w = Vec3(0, 1, 0);
            w = glm::normalize(w);
            break;
        }

        // The line: through a random point near the sweep, its origin well away from it.
        const Vec3 radial = randomPerpendicular(rng, n);
        const double z = length * std::pow(uniform(rng, 0.0, 1.0), 2.0) * 1.1 - 0.05 * length;
        const Vec3 anchor = ps + uniform(rng, -0.15, 1.15) * f + z * n + uniform(rng, 0.0, 1.3 * rBound) * radial;
        Line line{anchor - uniform(rng, 5.0, 60.0) * w, w};
        if (family == Family::DexelInFace) {
            line.origin.z = rng() % 2 ? ps.z + parts.front().za : ps.z + parts.back().zb;
        }
        if (family == Family::SymmetryPlane) {
            const int across = f.x != 0.0 ? 1 : 0;  // the coordinate the plane fixes
            line.origin[across] = ps[across];
        }

        const MoveSweep sweep(*tool, ps, ps + f, n);
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
                m << std::setprecision(17) << "case " << i << ": " << tool->description() << " ("
                  << models::name(kind) << ") start " << str(ps) << " feed " << str(f) << " axis " << str(n)
                  << "\n   " << str(*tool) << "\n   line " << str(line.origin) << " dir " << str(line.dir) << "\n   solver "
                  << str(s) << "\n   oracle " << str(t) << "\n";
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

TEST_CASE("sweep vs oracle: dexel lying in a flat face's plane", "[sweep][oracle]") {
    check(Family::DexelInFace, 109, 6000);
}

TEST_CASE("sweep vs oracle: cutting region and shank region", "[sweep][oracle]") {
    check(Family::Regions, 110, 10000);
}

TEST_CASE("sweep vs oracle: line in the move's plane of symmetry", "[sweep][oracle]") {
    check(Family::SymmetryPlane, 111, 8000);
}
