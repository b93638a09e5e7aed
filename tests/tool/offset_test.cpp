// A convex part of a tool grown by r (offsetPart), against the distance to the part measured by a
// polygon of its own.
//
// The oracle: the part's meridian half-section { 0 <= rho <= R(z), za <= z <= zb }, with R taken
// from the test's tool models (tests/sweep/tool_models.h, written from the builders' parameters,
// not from the profile pieces), is replaced by the polygon through points (R(z), z) sampled so that
// the section lies within kGap / 2 of it (polygonOf). R is concave on a convex part, so its chords
// lie inside the section: the distance D of a point to the part and the polygon's distance P
// satisfy P - kGap / 2 <= D <= P. The distance in space is the
// distance in the meridian plane (the part is a solid of revolution).
//
// Checks, for random tools of every kind, random radii and random lines through the grown part:
// the grown interval's ends lie at distance r from the part, and its midpoint within r; a line
// that the oracle puts farther than r from the part everywhere gets no interval.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "dexelmill/tool/offset.h"
#include "sweep/tool_models.h"

using namespace dexelmill;

namespace {

/// Twice the largest distance of the part's section from the oracle's polygon (mm).
constexpr double kGap = 1e-4;
/// Halvings of a span of the polygon: 2^-40 of a tool's length is far below kGap.
constexpr int kMaxDepth = 40;
/// Rounding of the grown interval's ends and of the oracle's polygon distance (mm): the root
/// finding of torus pieces stops at about 1e-13 of their size, far below this.
constexpr double kRound = 1e-7;
/// Spacing of the points a missed line is checked at (mm).
constexpr double kLineStep = 0.02;

struct Polygon {
    std::vector<double> rho, z;
};

/// The meridian boundary of one oracle part, bottom centre to top centre. On a span [z0, z1] the
/// curve's height above its chord, d(z), is concave and zero at both ends, so its largest value is
/// at most 2 d(midpoint) (were the peak at z* left of the midpoint, concavity on [z*, z1] puts
/// d(midpoint) at half of d(z*) or more; the same on the right). Spans are halved until that bound
/// is within kGap / 2, so the section lies within kGap / 2 of the polygon.
Polygon polygonOf(const oracle::Part& part) {
    Polygon poly;
    poly.rho.push_back(0.0), poly.z.push_back(part.za);
    poly.rho.push_back(part.radius(part.za)), poly.z.push_back(part.za);
    std::function<void(double, double, double, double, int)> sample = [&](double z0, double r0, double z1, double r1,
                                                                          int depth) {
        const double zm = 0.5 * (z0 + z1), rm = part.radius(zm);
        if (depth < kMaxDepth && 2.0 * (rm - 0.5 * (r0 + r1)) > kGap / 2) {
            sample(z0, r0, zm, rm, depth + 1);
            sample(zm, rm, z1, r1, depth + 1);
            return;
        }
        poly.rho.push_back(r1), poly.z.push_back(z1);
    };
    sample(part.za, part.radius(part.za), part.zb, part.radius(part.zb), 0);
    poly.rho.push_back(0.0), poly.z.push_back(part.zb);
    return poly;
}

double segmentDistance(double px, double py, double ax, double ay, double bx, double by) {
    const double dx = bx - ax, dy = by - ay, len2 = dx * dx + dy * dy;
    const double t = len2 > 0.0 ? std::clamp(((px - ax) * dx + (py - ay) * dy) / len2, 0.0, 1.0) : 0.0;
    return std::hypot(px - ax - t * dx, py - ay - t * dy);
}

/// The polygon's distance to the point (rho, z), rho >= 0: 0 inside; any value of at least `cap`
/// when the distance is at least `cap`. The lateral chain (vertices 1 .. n-2) rises monotonically,
/// and a segment is no nearer than its height gap, so the scan runs out from the point's height and
/// stops where that gap exceeds the best distance or the cap.
double polygonDistance(const Polygon& poly, double rho, double z, double cap) {
    const std::size_t n = poly.rho.size();
    double best = std::min({cap, segmentDistance(rho, z, poly.rho[0], poly.z[0], poly.rho[1], poly.z[1]),
                            segmentDistance(rho, z, poly.rho[n - 2], poly.z[n - 2], poly.rho[n - 1], poly.z[n - 1])});
    const auto first = poly.z.begin() + 1, last = poly.z.begin() + long(n - 1);
    const std::size_t at = std::size_t(std::lower_bound(first, last, z) - poly.z.begin());
    bool inside = z >= poly.z.front() && z <= poly.z.back();
    if (inside && at > 1 && at < n - 1) {
        const double z0 = poly.z[at - 1], z1 = poly.z[at];
        const double edge = z1 > z0 ? poly.rho[at - 1] + (poly.rho[at] - poly.rho[at - 1]) * (z - z0) / (z1 - z0)
                                    : std::max(poly.rho[at - 1], poly.rho[at]);
        inside = rho <= edge;
    } else if (inside) {
        inside = rho <= poly.rho[at <= 1 ? 1 : n - 2];
    }
    if (inside) return 0.0;
    for (std::size_t i = std::max<std::size_t>(at, 2); i < n - 1; ++i) {  // segments (i-1, i) upwards
        if (poly.z[i - 1] - z > best) break;
        best = std::min(best, segmentDistance(rho, z, poly.rho[i - 1], poly.z[i - 1], poly.rho[i], poly.z[i]));
    }
    for (std::size_t i = std::min(at, n - 2); i >= 2; --i) {  // segments (i-1, i) downwards
        if (z - poly.z[i] > best) break;
        best = std::min(best, segmentDistance(rho, z, poly.rho[i - 1], poly.z[i - 1], poly.rho[i], poly.z[i]));
    }
    return best;
}

/// The tool frame's meridian coordinates of a point: tip at the origin, axis +z.
double rhoOf(const Vec3& p) { return std::hypot(p.x, p.y); }

/// Line l of a batch: through a random point near the part (within 2 r of its section's box), at
/// parameter 100; every fourth along the axis, the next across it, the others at random. False
/// where the random direction is too short to normalise.
bool randomLineNear(const oracle::Part& part, double r, int l, std::mt19937_64& rng, Line& line) {
    const double zc = models::uniform(rng, part.za - 2 * r, part.zb + 2 * r);
    const double rc = models::uniform(rng, 0.0, part.rBound + 2 * r);
    const Vec3 through(rc, 0.0, zc);
    Vec3 dir(models::uniform(rng, -1, 1), models::uniform(rng, -1, 1), models::uniform(rng, -1, 1));
    if (l % 4 == 0) dir = Vec3(0.0, 0.0, 1.0);  // along the axis
    if (l % 4 == 1) dir = Vec3(0.0, 1.0, 0.0);  // across it
    if (glm::length(dir) < 1e-3) return false;
    dir = glm::normalize(dir);
    line = Line{through - 100.0 * dir, dir};
    return true;
}

std::string describe(const Line& line) {
    std::ostringstream out;
    const Vec3 through = line.at(100.0);
    out << "line through (" << through.x << ", " << through.y << ", " << through.z << ") along (" << line.dir.x
        << ", " << line.dir.y << ", " << line.dir.z << ")";
    return out.str();
}

/// For a line given no interval: no point of it near the part is within r of the part by the
/// oracle's `distance` (the polygon, never nearer than the part).
template <class Distance>
void checkNothingWithin(const oracle::Part& part, double r, Distance&& distance) {
    const double reach = part.zb - part.za + part.rBound + 3 * r;
    for (double t = 100.0 - reach; t <= 100.0 + reach; t += kLineStep)
        if (distance(t) < r - kRound) FAIL_CHECK("within r at t = " << t);
}

/// For a line's interval: both ends are outside the grown part (at least r from the part, by the
/// oracle's `distance`, which includes up to kGap / 2 of the polygon's) and within `reach` of it.
template <class Distance>
void checkEnds(const Interval& iv, double r, double reach, Distance&& distance) {
    for (const double t : {iv.lo, iv.hi}) {
        const double d = distance(t);
        INFO("end t = " << t << " of [" << iv.lo << ", " << iv.hi << "]");
        CHECK(d >= r - kRound);
        CHECK(d - kGap / 2 <= reach + kRound);
    }
}

/// For `perKind` random tools of every kind, a random growth r in [rMin, 5] per part and 20
/// random lines near it: the line's interval in the pieces grow(tool, part, r) gives, checked by
/// checkHit(interval, r, distance) (distance: the oracle's, from the line parameter), or, where
/// empty, no point of the line within r of the part.
template <class Grow, class CheckHit>
void checkGrownParts(std::uint64_t seed, int perKind, double rMin, Grow&& grow, CheckHit&& checkHit) {
    std::mt19937_64 rng(seed);
    int checked = 0, missed = 0;
    for (int k = 0; k < int(models::Kind::Count); ++k) {
        for (int n = 0; n < perKind; ++n) {
            const models::Model m = models::make(models::Kind(k), rng);
            REQUIRE(m.parts.size() == m.tool.convexParts().size());
            for (std::size_t p = 0; p < m.parts.size(); ++p) {
                const oracle::Part& part = m.parts[p];
                const Polygon poly = polygonOf(part);
                const double r = std::exp(models::uniform(rng, std::log(rMin), std::log(5.0)));
                const std::vector<ProfilePiece> grown = grow(m.tool, m.tool.convexParts()[p], r);
                for (int l = 0; l < 20; ++l) {
                    Line line;
                    if (!randomLineNear(part, r, l, rng, line)) continue;
                    const Interval iv = intersectPieces(grown, LocalLine::make(ToolPose{}, line));
                    INFO(models::name(models::Kind(k)) << " part " << p << " r " << r << " " << describe(line));
                    auto distance = [&](double t) {
                        const Vec3 q = line.at(t);
                        return polygonDistance(poly, rhoOf(q), q.z, 2.0 * r + kGap);
                    };
                    if (iv.isEmpty()) {
                        checkNothingWithin(part, r, distance);
                        ++missed;
                        continue;
                    }
                    checkHit(iv, r, distance);
                    ++checked;
                }
            }
        }
    }
    CHECK(checked > 1000);
    CHECK(missed > 10);
}

}  // namespace

TEST_CASE("offsetPart: a grown convex part ends at distance r from the part", "[tool][offset]") {
    checkGrownParts(20261123, std::max(2, int(40 * oracle::testScale())), 1e-4, offsetPart,
                    [](const Interval& iv, double r, const auto& distance) {
                        checkEnds(iv, r, r, distance);
                        CHECK(distance(0.5 * (iv.lo + iv.hi)) - kGap / 2 <= r + kRound);
                    });
}

TEST_CASE("offsetPart: growing by zero keeps the part, and a flat end mill's grown disk has rounded rims",
          "[tool][offset]") {
    const Tool flat = flatEndMill(10.0, {20.0, 20.0});
    const ConvexPart& part = flat.convexParts().front();
    // A line across the axis at the tip's height: the disk of radius 5, grown by 1 to 6.
    const Line across{Vec3(-50.0, 0.0, 0.0), Vec3(1.0, 0.0, 0.0)};
    const Interval bare = intersectPieces(offsetPart(flat, part, 0.0), LocalLine::make(ToolPose{}, across));
    CHECK(bare.lo == Approx(45.0));
    CHECK(bare.hi == Approx(55.0));
    const Interval grown = intersectPieces(offsetPart(flat, part, 1.0), LocalLine::make(ToolPose{}, across));
    CHECK(grown.lo == Approx(44.0));
    CHECK(grown.hi == Approx(56.0));
    // 0.6 below the bottom, the rim's torus of radius 1: half-width 5 + sqrt(1 - 0.36) = 5.8.
    const Line below{Vec3(-50.0, 0.0, -0.6), Vec3(1.0, 0.0, 0.0)};
    const Interval rim = intersectPieces(offsetPart(flat, part, 1.0), LocalLine::make(ToolPose{}, below));
    CHECK(rim.hi - 50.0 == Approx(5.8));
    // Along the axis: from 1 below the tip to 1 above the top.
    const Line axis{Vec3(0.0, 0.0, -50.0), Vec3(0.0, 0.0, 1.0)};
    const Interval along = intersectPieces(offsetPart(flat, part, 1.0), LocalLine::make(ToolPose{}, axis));
    CHECK(along.lo == Approx(49.0));
    CHECK(along.hi == Approx(71.0));
}

TEST_CASE("outerOffsetPart: holds the grown part and lies within r + slack of the part; allPiecesHeld",
          "[tool][offset]") {
    std::mt19937_64 rng(20261124);
    const int perKind = std::max(2, int(30 * oracle::testScale()));
    int checked = 0, missed = 0, coned = 0, kept = 0, windowsAccepted = 0, windowsRefused = 0;
    int hintedAccepted = 0, hintedRefused = 0;
    for (int k = 0; k < int(models::Kind::Count); ++k) {
        for (int n = 0; n < perKind; ++n) {
            const models::Model m = models::make(models::Kind(k), rng);
            for (std::size_t p = 0; p < m.parts.size(); ++p) {
                const oracle::Part& part = m.parts[p];
                const Polygon poly = polygonOf(part);
                const double r = std::exp(models::uniform(rng, std::log(1e-3), std::log(5.0)));
                const double slack = r * std::exp(models::uniform(rng, std::log(0.01), std::log(0.5)));
                const auto outer = outerOffsetPart(m.tool, m.tool.convexParts()[p], r, slack);
                const auto grown = offsetPart(m.tool, m.tool.convexParts()[p], r);
                for (std::size_t i = 0; i < outer.pieces.size(); ++i) {
                    const auto* a = std::get_if<ArcPiece>(&outer.pieces[i]);
                    if (a && a->rc > 0.0) (outer.chains[i].empty() ? kept : coned) += 1;
                }
                for (int l = 0; l < 20; ++l) {
                    Line line;
                    if (!randomLineNear(part, r, l, rng, line)) continue;
                    const LocalLine local = LocalLine::make(ToolPose{}, line);
                    const Interval iv = intersectOuter(outer, local);
                    // allPiecesHeld against a random window W: accepting means the grown part's
                    // exact interval lies in W; and W holding intersectOuter's interval means accepting.
                    {
                        const Interval exact = intersectPieces(grown, local);
                        const Interval base = iv.isEmpty() ? Interval{99.0, 101.0} : iv;
                        const double spread = 2.0 * (r + slack);
                        const Interval window{base.lo + models::uniform(rng, -spread, spread),
                                              base.hi + models::uniform(rng, -spread, spread)};
                        const bool accepted = allPiecesHeld(outer, local, [&](const Interval& x) {
                            return x.isEmpty() || (x.lo >= window.lo && x.hi <= window.hi);
                        });
                        if (accepted && !exact.isEmpty()) {
                            CHECK(exact.lo >= window.lo);
                            CHECK(exact.hi <= window.hi);
                        }
                        if (iv.isEmpty() || (iv.lo >= window.lo && iv.hi <= window.hi)) CHECK(accepted);
                        (accepted ? windowsAccepted : windowsRefused) += 1;
                        // With the root finding's hint, the ungrown part's interval as the turning
                        // sweep gives it: accepting still means the grown part lies in W, by the
                        // oracle (the line's points just outside W are farther than r from the
                        // part), and W holding both the interval without the hint and the exact one
                        // with the slack both sides (a root-found torus's ends move within it)
                        // still means accepting.
                        const Interval inside = m.tool.intersectPart(m.tool.convexParts()[p], local);
                        const bool hinted = allPiecesHeld(
                            outer, local,
                            [&](const Interval& x) { return x.isEmpty() || (x.lo >= window.lo && x.hi <= window.hi); },
                            inside);
                        if (hinted) {
                            for (const double t : {window.lo - kLineStep, window.hi + kLineStep}) {
                                const Vec3 q = line.at(t);
                                CHECK(polygonDistance(poly, rhoOf(q), q.z, 2.0 * r + kGap) >= r - kRound);
                            }
                        }
                        const auto within = [&](const Interval& x, double pad) {
                            return x.isEmpty() || (x.lo - pad >= window.lo && x.hi + pad <= window.hi);
                        };
                        if (within(iv, 0.0) && within(exact, slack)) CHECK(hinted);
                        if (!inside.isEmpty()) (hinted ? hintedAccepted : hintedRefused) += 1;
                    }
                    INFO(models::name(models::Kind(k)) << " part " << p << " r " << r << " slack " << slack << " "
                                                       << describe(line));
                    auto distance = [&](double t) {
                        const Vec3 q = line.at(t);
                        return polygonDistance(poly, rhoOf(q), q.z, 2.0 * (r + slack) + kGap);
                    };
                    if (iv.isEmpty()) {
                        checkNothingWithin(part, r, distance);
                        ++missed;
                        continue;
                    }
                    // Ends: outside the grown part (a superset's boundary), within r + slack of the part.
                    checkEnds(iv, r, r + slack, distance);
                    // The line's points just outside the interval are farther than r from the part.
                    for (const double t : {iv.lo - kLineStep, iv.hi + kLineStep}) CHECK(distance(t) >= r - kRound);
                    ++checked;
                }
            }
        }
    }
    CHECK(checked > 1000);
    CHECK(missed > 10);
    CHECK(coned > 0);
    CHECK(kept > 0);  // tori whose chain would need more than kMaxTangentCones cones stay
    CHECK(windowsAccepted > 500);
    CHECK(windowsRefused > 500);
    CHECK(hintedAccepted > 300);
    CHECK(hintedRefused > 300);
}

TEST_CASE("outerOffsetPart: a flat end mill's rims get two cones each, used where a line crosses them",
          "[tool][offset]") {
    const Tool flat = flatEndMill(10.0, {20.0, 20.0});
    const ConvexPart& part = flat.convexParts().front();
    const OuterPart outer = outerOffsetPart(flat, part, 1.0, 0.1);
    const auto grown = offsetPart(flat, part, 1.0);
    REQUIRE(outer.pieces.size() == grown.size());
    REQUIRE(outer.chains.size() == grown.size());
    for (std::size_t i = 0; i < grown.size(); ++i)
        CHECK(outer.chains[i].size() == (std::holds_alternative<ArcPiece>(grown[i]) ? 2u : 0u));
    // Rims of 90 degrees in two steps of 45: meeting points 1 / cos(22.5 deg) from the rim's centre.
    const double meet = 1.0 / std::cos(std::acos(-1.0) / 8.0);
    // A line that leaves through the bottom rim's torus, rising across the axis: the chain's
    // interval holds the torus's, ends later, and its end lies within `meet` of the rim's circle.
    const Line rising{Vec3(-50.0, 0.0, -1.6), glm::normalize(Vec3(1.0, 0.0, 0.02))};
    const LocalLine local = LocalLine::make(ToolPose{}, rising);
    const Interval exact = intersectPieces(grown, local);
    const Interval rim = intersectOuter(outer, local);
    REQUIRE(!exact.isEmpty());
    CHECK(rim.lo <= exact.lo);
    CHECK(rim.hi > exact.hi);
    const Vec3 end = rising.at(rim.hi);
    CHECK(end.z < 0.0);
    CHECK(std::hypot(std::hypot(end.x, end.y) - 5.0, end.z) <= meet + 1e-12);
    // Closed forms stay exact: across the bottom face, and along the axis.
    const Line across{Vec3(-50.0, 0.0, 0.0), Vec3(1.0, 0.0, 0.0)};
    CHECK(intersectOuter(outer, LocalLine::make(ToolPose{}, across)).hi == Approx(56.0));
    const Line axis{Vec3(0.0, 0.0, -50.0), Vec3(0.0, 0.0, 1.0)};
    const Interval along = intersectOuter(outer, LocalLine::make(ToolPose{}, axis));
    CHECK(along.lo == Approx(49.0));
    CHECK(along.hi == Approx(71.0));
    // No slack: no chains.
    for (const auto& chain : outerOffsetPart(flat, part, 1.0, 0.0).chains) CHECK(chain.empty());
}

TEST_CASE("mitredOffsetPart: holds the grown part and lies within r sqrt 2 of the part", "[tool][offset]") {
    // Down to a millionth of the part's size: the growths a turning sweep's last levels ask for.
    const auto grow = [](const Tool& tool, const ConvexPart& part, double r) {
        std::vector<ProfilePiece> mitred = mitredOffsetPart(tool, part, r);
        // A chain: each piece starts where the one below ends (to rounding: a grown arc's ends
        // are scaled from its centre, a corner's steps stepped from the corner).
        for (std::size_t i = 1; i < mitred.size(); ++i)
            CHECK(std::abs(pieceZ0(mitred[i]) - pieceZ1(mitred[i - 1])) <= kRound);
        return mitred;
    };
    checkGrownParts(20261129, std::max(2, int(30 * oracle::testScale())), 1e-6, grow,
                    [](const Interval& iv, double r, const auto& distance) {
                        checkEnds(iv, r, std::sqrt(2.0) * r, distance);
                        for (const double t : {iv.lo - kLineStep, iv.hi + kLineStep})
                            CHECK(distance(t) >= r - kRound);
                    });
}

TEST_CASE("clipChain and mitredOffsetChain: a band of heights cut from a part, and grown", "[tool][offset]") {
    // The band of a part between two random heights (the turning sweep's bands, turning.cpp note
    // i), against the oracle's part cut to the same heights: the chain spans exactly those
    // heights, its radius is the oracle's, and grown it ends between r and r sqrt 2 of the band;
    // with its tori as chains of cones within a slack of 4 r, between r and 5 r.
    std::mt19937_64 rng(20261130);
    int checked = 0;
    for (int k = 0; k < int(models::Kind::Count); ++k) {
        for (int n = 0; n < std::max(2, int(20 * oracle::testScale())); ++n) {
            const models::Model m = models::make(models::Kind(k), rng);
            for (std::size_t p = 0; p < m.parts.size(); ++p) {
                const ConvexPart& part = m.tool.convexParts()[p];
                const double za = m.parts[p].za, zb = m.parts[p].zb;
                const double lo = models::uniform(rng, za, za + 0.6 * (zb - za)), hi = models::uniform(rng, lo + 0.2 * (zb - za), zb);
                const std::vector<ProfilePiece> band = clipChain(m.tool.pieces(), part.first, part.last, lo, hi);
                const oracle::Part cut = models::clip({m.parts[p]}, lo, hi).front();
                INFO(models::name(models::Kind(k)) << " part " << p << " band [" << lo << ", " << hi << "]");
                REQUIRE(!band.empty());
                CHECK(pieceZ0(band.front()) == lo);
                CHECK(pieceZ1(band.back()) == hi);
                for (std::size_t i = 1; i < band.size(); ++i) CHECK(pieceZ0(band[i]) == pieceZ1(band[i - 1]));
                for (const ProfilePiece& piece : band)
                    for (const double s : {0.0, 0.3, 1.0}) {
                        const double z = pieceZ0(piece) + s * (pieceZ1(piece) - pieceZ0(piece));
                        CHECK(std::abs(pieceRadius(piece, z) - cut.radius(z)) <= kRound);
                    }
                const Polygon poly = polygonOf(cut);
                const double r = std::exp(models::uniform(rng, std::log(1e-6), std::log(5.0)));
                const std::vector<ProfilePiece> grown = mitredOffsetChain(band, r);
                const std::vector<ProfilePiece> coned = mitredOffsetChain(band, r, 4.0 * r, 12);
                for (int l = 0; l < 20; ++l) {
                    Line line;
                    if (!randomLineNear(cut, r, l, rng, line)) continue;
                    auto distance = [&](double t) {
                        const Vec3 q = line.at(t);
                        return polygonDistance(poly, rhoOf(q), q.z, 5.0 * r + kGap);
                    };
                    for (const bool cones : {false, true}) {
                        INFO((cones ? "tori as cones" : "tori kept"));
                        const Interval iv = intersectPieces(cones ? coned : grown, LocalLine::make(ToolPose{}, line));
                        if (iv.isEmpty()) {
                            checkNothingWithin(cut, r, distance);
                            continue;
                        }
                        checkEnds(iv, r, (cones ? 5.0 : std::sqrt(2.0)) * r, distance);
                        for (const double t : {iv.lo - kLineStep, iv.hi + kLineStep}) CHECK(distance(t) >= r - kRound);
                        ++checked;
                    }
                }
            }
        }
    }
    CHECK(checked > 2000);
}

TEST_CASE("mitredOffsetChain: a bull nose's torus as a chain of cones, where few enough keep to the slack",
          "[tool][offset]") {
    // A bull nose D10 r2: its corner, a quarter turn of radius 2 about (3, 2), grown by 1 to
    // radius 3. Steps d with 3 (1 / cos(d / 2) - 1) <= slack: 0.3 allows a quarter turn in two
    // (3 / cos(22.5 deg) - 3 = 0.247), 0.1 needs four (0.0445; three steps stray 0.106).
    const Tool bull = bullNoseEndMill(10.0, 2.0, {20.0, 20.0});
    const ConvexPart& part = bull.convexParts().front();
    const std::vector<ProfilePiece> chain(bull.pieces().begin() + std::ptrdiff_t(part.first),
                                          bull.pieces().begin() + std::ptrdiff_t(part.last));
    const auto tori = [](const std::vector<ProfilePiece>& pieces) {
        int n = 0;
        for (const ProfilePiece& p : pieces) n += std::holds_alternative<ArcPiece>(p);
        return n;
    };
    const auto kept = mitredOffsetChain(chain, 1.0);
    CHECK(tori(kept) == 1);
    const auto two = mitredOffsetChain(chain, 1.0, 0.3, 2);
    CHECK(tori(two) == 0);
    CHECK(tori(mitredOffsetChain(chain, 1.0, 0.3, 1)) == 1);  // two steps needed, one allowed
    CHECK(tori(mitredOffsetChain(chain, 1.0, 0.1, 3)) == 1);  // four needed, three allowed
    const auto four = mitredOffsetChain(chain, 1.0, 0.1, 4);
    CHECK(tori(four) == 0);
    // Out from the corner's centre through a chain's first vertex, at the normal angle
    // -90 degrees + d / 2, the chain reaches 3 / cos(d / 2), beyond the torus by at most the slack.
    const double pi = std::acos(-1.0);
    for (const auto* coned : {&two, &four}) {
        const double d = 0.5 * pi / (coned == &two ? 2 : 4), slack = coned == &two ? 0.3 : 0.1;
        const Vec3 out(std::cos(0.5 * d - 0.5 * pi), 0.0, std::sin(0.5 * d - 0.5 * pi));
        const Line ray{Vec3(3.0, 0.0, 2.0) - 50.0 * out, out};
        const double torus = intersectPieces(kept, LocalLine::make(ToolPose{}, ray)).hi;
        const double hi = intersectPieces(*coned, LocalLine::make(ToolPose{}, ray)).hi;
        CHECK(torus == Approx(53.0));
        CHECK(hi == Approx(50.0 + 3.0 / std::cos(0.5 * d)));
        CHECK(hi - torus <= slack);
    }
    // A sphere (an arc on the axis) stays an arc: its sweep is a capsule's, in closed form.
    const Tool ball = ballEndMill(6.0, {20.0, 20.0});
    const ConvexPart& bp = ball.convexParts().front();
    const std::vector<ProfilePiece> ballChain(ball.pieces().begin() + std::ptrdiff_t(bp.first),
                                              ball.pieces().begin() + std::ptrdiff_t(bp.last));
    CHECK(tori(mitredOffsetChain(ballChain, 1.0, 4.0, 12)) == 1);
}

TEST_CASE("mitredOffsetChain: a step level to rounding after a widening cone keeps that cone's surface",
          "[tool][offset]") {
    // An arc of radius 2 about (3, 2) from normal angle -0.3 nearly to the top (pi / 2 - 1e-7),
    // grown by 1 and taken as one pair of tangents (a slack of 10 allows it): the tangent at -0.3
    // rises outwards to where it meets the one at the top, which then runs inwards rising 1e-7 mm
    // per mm, about 4e-7 mm in all: less than the chain's level step (1e-6 r), so no cone of its
    // own. The first cone must still reach the meeting point: raising its top to the arc's end
    // without widening it once left that point 5e-7 mm outside.
    const double a = -0.3, b = 0.5 * std::acos(-1.0) - 1e-7;
    const std::vector<ProfilePiece> chain{ArcPiece{2.0 + 2.0 * std::sin(a), 2.0 + 2.0 * std::sin(b), 3.0, 2.0, 2.0}};
    const auto coned = mitredOffsetChain(chain, 1.0, 10.0, 1);
    for (const ProfilePiece& p : coned) CHECK(std::holds_alternative<ConePiece>(p));
    const double far = 3.0 / std::cos(0.5 * (b - a)), mid = 0.5 * (a + b);
    const double rMeet = 3.0 + far * std::cos(mid), zMeet = 2.0 + far * std::sin(mid);
    double radius = -1.0;
    for (const ProfilePiece& p : coned)
        if (zMeet >= pieceZ0(p) && zMeet <= pieceZ1(p)) radius = std::max(radius, pieceRadius(p, zMeet));
    CHECK(radius >= rMeet - 1e-12);
    // And the chain ends at the grown arc's top, 1e-7 from the axis side of it.
    CHECK(pieceZ1(coned.back()) >= 2.0 + 3.0 * std::sin(b) - 1e-12);
}

TEST_CASE("mitredOffsetPart: a flat end mill grows into a cylinder with square corners", "[tool][offset]") {
    const Tool flat = flatEndMill(10.0, {20.0, 20.0});
    const ConvexPart& part = flat.convexParts().front();
    // Each rim turns the normal a quarter turn: one step, the two faces' planes moved out by r
    // meeting at the corner (r sqrt 2 from the rim). The faces need no piece; the side is the
    // rims' steps and the cylinder moved out, all at radius 6.
    const auto mitred = mitredOffsetPart(flat, part, 1.0);
    REQUIRE(mitred.size() == 3);
    const double z[] = {-1.0, 0.0, 20.0, 21.0};
    for (std::size_t i = 0; i < mitred.size(); ++i) {
        REQUIRE(std::holds_alternative<ConePiece>(mitred[i]));
        const ConePiece& c = std::get<ConePiece>(mitred[i]);
        CHECK(c.z0 == Approx(z[i]));
        CHECK(c.z1 == Approx(z[i + 1]));
        CHECK(c.r0 == Approx(6.0));
        CHECK(c.r1 == Approx(6.0));
    }
    // The corner of the grown solid lies r sqrt 2 from the rim: along a line through it, the
    // interval reaches it where the rounded offset (offsetPart) stops r short of it.
    const Vec3 corner(6.0, 0.0, -1.0), out = glm::normalize(Vec3(1.0, 0.0, -1.0));
    const Line diagonal{corner - 50.0 * out, out};
    CHECK(intersectPieces(mitred, LocalLine::make(ToolPose{}, diagonal)).hi == Approx(50.0));
    CHECK(intersectPieces(offsetPart(flat, part, 1.0), LocalLine::make(ToolPose{}, diagonal)).hi ==
          Approx(50.0 - (std::sqrt(2.0) - 1.0)));
    // Growing by zero keeps the part.
    const auto same = mitredOffsetPart(flat, part, 0.0);
    REQUIRE(same.size() == 1);
    CHECK(std::get<ConePiece>(same.front()).r0 == 5.0);
}

TEST_CASE("outerOffsetPart: no tangent cone is nearly level, however small the growth against the tool's heights",
          "[tool][offset]") {
    // A chain's cones follow the corner's tangents, at most kMaxTangentCones a quarter turn, so
    // none is flatter than about a sixth of a turn, except a step level to rounding at a face,
    // which is merged. A drill 13.4 mm long grown by 1.3e-4 mm once made a cone 1e-9 mm high and
    // 5e-5 mm across at its top rim, when the corner's angles were read back from the grown arc's
    // heights (asin next to 1); the turning sweep's oracle found an end 1.5e-3 mm outside.
    const Tool tools[] = {drill(1.02463, 104.477 * std::acos(-1.0) / 180.0, {13.355630114072722, 13.355630114072722}),
                          flatEndMill(10.0, {100.0, 100.0}), bullNoseEndMill(10.0, 2.0, {60.0, 100.0}),
                          chamferMill(0.5, 0.6, 8.0, {40.0, 80.0})};
    int cones = 0;
    for (const Tool& tool : tools)
        for (const ConvexPart& part : tool.convexParts())
            for (const double r : {1e-6, 1e-5, 1.3e-4, 1e-3, 0.1}) {
                const OuterPart outer = outerOffsetPart(tool, part, r, 0.1 * r);
                for (const auto& chain : outer.chains)
                    for (const ConePiece& c : chain) {
                        INFO(tool.description() << " r " << r << " cone z " << c.z0 << " .. " << c.z1 << " r " << c.r0
                                                << " .. " << c.r1);
                        CHECK(std::abs(c.r1 - c.r0) <= 10.0 * (c.z1 - c.z0));
                        ++cones;
                    }
            }
    CHECK(cones > 50);
}
