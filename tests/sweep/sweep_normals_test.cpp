// The sweep's Hermite data against the brute-force oracle (oracle.h): for the random cases of the
// interval tests (oracle_cases.h), the normal the solver gives at each end of a part's interval is
// compared with the oracle's tangent plane there, found by finite differences. Shares no code with
// the solver: the oracle's own ends are found on lines parallel to the query line.
//
// The finite differences: the query line offset by kStep along two unit vectors a, b perpendicular
// to it and to each other, both ways, meets the swept part's boundary near the end at P(+-a),
// P(+-b); P(+a) - P(-a) and P(+b) - P(-b) span the tangent plane (central differences, whose error
// is of order kStep^2 times the squared curvature, 1e-6 rad at a radius of 0.1 mm). The oracle's
// ends are bisected to 1e-13 mm, but its golden section over the feed leaves an end off by up to
// about 2e-9 mm / c (c: the sine of the angle between the line and the surface), so the difference
// normal is good to about 4e-5 / c rad.
//
// Where the surface bends within the stencil, the normals of its two halves differ: n(+) from
// P(+a) - P(0) and P(+b) - P(0), n(-) from P(0) - P(-a) and P(0) - P(-b). Their angle, the turn,
// is about kStep times the curvature on a smooth surface and as large as the crease's angle where
// an end lies within kStep of a crease. The solver's normal must lie within kAngle plus the turn of
// the central difference normal. An end whose turn exceeds kCreaseTurn is on a crease as far as
// the oracle can tell, and one whose line meets the surface at a sine below kGrazing has no good
// difference normal: both are skipped, counted, and must be few.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <random>
#include <sstream>

#include "dexelmill/sweep/sweep.h"
#include "oracle.h"
#include "oracle_cases.h"

using namespace dexelmill;
using namespace cases;

namespace {

constexpr double kStep = 1e-4;        ///< finite-difference offset (mm)
constexpr double kAngle = 1e-3;       ///< tolerance on the angle to the difference normal (rad)
constexpr double kCreaseTurn = 0.05;  ///< a larger turn across the stencil: a crease (rad)
constexpr double kGrazing = 0.05;     ///< a smaller sine between line and surface: grazing
constexpr double kBracket = 0.05;     ///< how far past an end the bisections start outside (mm)
constexpr int kBisect = 45;           ///< halvings of brackets under 0.1 mm: below 1e-13 mm

double angle(const Vec3& a, const Vec3& b) {
    return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

/// The oracle's end of one part's removed interval on `line`, between a parameter inside the part's
/// sweep and one outside: bisection on the sign of Phi. Empty when the two are not on either side.
std::optional<double> oracleEnd(const oracle::Part& part, const oracle::Motion& m, const Line& line, double inside,
                                double outside) {
    if (!(oracle::phi(part, m, line, inside) <= 0.0) || oracle::phi(part, m, line, outside) <= 0.0) return {};
    for (int i = 0; i < kBisect; ++i) {
        const double mid = 0.5 * (inside + outside);
        (oracle::phi(part, m, line, mid) <= 0.0 ? inside : outside) = mid;
    }
    return 0.5 * (inside + outside);
}

struct NormalResult {
    int cases = 0, ends = 0, checked = 0, creases = 0, grazing = 0, unbracketed = 0, failures = 0;
    int sharp = 0, sharpOnCrease = 0;  ///< ends marked sharp; of them, on a crease as the oracle sees it
    double worst = 0.0;  ///< the largest angle between a checked normal and the oracle's (rad)
    std::string firstFailures;
};

NormalResult runNormals(Family family, std::uint64_t seed, int count) {
    std::mt19937_64 rng(seed);
    NormalResult res;
    for (int i = 0; i < count; ++i) {
        const Case c = makeCase(family, rng);
        const MoveSweep sweep(c.tool(), c.ps, c.ps + c.f, c.n);
        LineHit hits[MoveSweep::kMaxParts];
        const std::size_t np = sweep.intersectParts(c.line, hits);
        ++res.cases;
        if (np != c.parts.size()) continue;
        const oracle::Motion motion{c.ps, c.f, c.n};
        const Vec3& w = c.line.dir;
        const Vec3 a = glm::normalize(glm::cross(w, std::abs(w.x) < 0.6 ? Vec3(1, 0, 0) : Vec3(0, 1, 0)));
        const Vec3 b = glm::cross(w, a);
        for (std::size_t k = 0; k < np; ++k) {
            const LineHit& hit = hits[k];
            if (hit.isEmpty()) continue;
            for (const bool hi : {false, true}) {
                ++res.ends;
                const Vec3 normal = hi ? hit.normalHi : hit.normalLo;
                res.sharp += hi ? hit.sharpHi : hit.sharpLo;
                const double v = hi ? hit.range.hi : hit.range.lo;
                const double sense = hi ? 1.0 : -1.0;  // outward along the line
                const double inside = v - sense * std::min(0.5 * hit.range.length(), kBracket);
                const double outside = v + sense * kBracket;
                // The oracle's ends on the line and on the four offset lines.
                const Vec3 offsets[5] = {Vec3(0.0), a, -a, b, -b};
                Vec3 p[5];
                bool bracketed = true;
                for (int j = 0; j < 5 && bracketed; ++j) {
                    const Line offset{c.line.origin + kStep * offsets[j], w};
                    const std::optional<double> end = oracleEnd(c.parts[k], motion, offset, inside, outside);
                    if (end) p[j] = offset.at(*end);
                    bracketed = end.has_value();
                }
                if (!bracketed) {
                    ++res.unbracketed;
                    continue;
                }
                Vec3 central = glm::normalize(glm::cross(p[1] - p[2], p[3] - p[4]));
                if (glm::dot(central, w) * sense < 0.0) central = -central;
                const double turn = angle(glm::cross(p[1] - p[0], p[3] - p[0]), glm::cross(p[0] - p[2], p[0] - p[4]));
                if (turn > kCreaseTurn) {
                    ++res.creases;
                    res.sharpOnCrease += hi ? hit.sharpHi : hit.sharpLo;
                    continue;
                }
                if (std::abs(glm::dot(central, w)) < kGrazing) {
                    ++res.grazing;
                    continue;
                }
                ++res.checked;
                const double err = angle(normal, central);
                res.worst = std::max(res.worst, err);
                const bool unit = std::abs(glm::length(normal) - 1.0) <= 1e-12;
                if ((err <= kAngle + turn && unit) || ++res.failures > 5) continue;
                std::ostringstream m;
                m << "case " << i << ", part " << k << (hi ? " hi" : " lo") << ": " << describe(c) << "\n   end "
                  << str(c.line.at(v)) << ((hi ? hit.sharpHi : hit.sharpLo) ? " sharp" : "") << " normal "
                  << str(normal) << "\n   oracle " << str(central) << " turn " << turn << ", angle " << err << "\n";
                res.firstFailures += m.str();
            }
        }
    }
    return res;
}

/// Runs a family. Its lines are random, so that they rarely end on a crease, unless
/// `throughCreases`: then the ends marked sharp must be those on a crease as the oracle sees it.
void checkNormals(Family family, std::uint64_t seed, int baseCount, bool throughCreases = false) {
    const int count = std::max(1, int(baseCount * oracle::testScale()));
    const NormalResult r = runNormals(family, seed, count);
    const int skipped = r.creases + r.grazing + r.unbracketed;
    INFO(r.cases << " cases, " << r.ends << " interval ends: " << r.checked << " checked (worst angle " << r.worst
                 << " rad), " << r.creases << " on an oracle crease, " << r.grazing << " grazing, " << r.unbracketed
                 << " unbracketed; " << r.sharp << " marked sharp (" << r.sharpOnCrease << " on an oracle crease); "
                 << r.failures << " wrong\n"
                 << r.firstFailures);
    CHECK(r.failures == 0);
    // Most ends are checked.
    CHECK(r.ends >= r.cases / 2);
    CHECK(r.checked >= 0.9 * r.ends);
    CHECK(skipped <= 0.1 * r.ends);
    if (throughCreases) CHECK(r.sharpOnCrease == r.sharp);
    else CHECK(r.sharp <= 0.01 * r.ends);
}

}  // namespace

TEST_CASE("sweep normals vs oracle: general moves, any axis, any line direction", "[sweep][oracle]") {
    checkNormals(Family::General, 201, 2000);
}

TEST_CASE("sweep normals vs oracle: 3-axis moves with x, y, z lines", "[sweep][oracle]") {
    checkNormals(Family::ThreeAxis, 202, 1200);
}

TEST_CASE("sweep normals vs oracle: horizontal moves", "[sweep][oracle]") {
    checkNormals(Family::Horizontal, 203, 800);
}

TEST_CASE("sweep normals vs oracle: plunges and retracts", "[sweep][oracle]") {
    checkNormals(Family::Plunge, 204, 500);
}

TEST_CASE("sweep normals vs oracle: zero-length moves", "[sweep][oracle]") {
    checkNormals(Family::ZeroLength, 205, 500);
}

TEST_CASE("sweep normals vs oracle: lines along the move", "[sweep][oracle]") {
    checkNormals(Family::DexelAlongMove, 206, 500);
}

TEST_CASE("sweep normals vs oracle: lines along the tool axis", "[sweep][oracle]") {
    checkNormals(Family::DexelAlongAxis, 207, 500);
}

TEST_CASE("sweep normals vs oracle: nearly degenerate moves and lines", "[sweep][oracle]") {
    checkNormals(Family::NearDegenerate, 208, 1500);
}

TEST_CASE("sweep normals vs oracle: cutting region and shank region", "[sweep][oracle]") {
    checkNormals(Family::Regions, 209, 600);
}

TEST_CASE("sweep normals vs oracle: lines in the move's plane of symmetry", "[sweep][oracle]") {
    // In the plane of the tool axis and the feed, a line crosses the path of a cone's apex (a V-bit's,
    // a drill's), a crease of the sweep, wherever the two are not parallel.
    checkNormals(Family::SymmetryPlane, 210, 600, true);
}
