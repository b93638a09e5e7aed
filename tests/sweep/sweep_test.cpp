// The sweep solver on hand-worked cases: one per envelope part and per degenerate case of
// method.md section 5. Expected values are derived in the comments, not taken from the code.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

#include "dexelmill/error.h"
#include "dexelmill/sweep/sweep.h"
#include "dexelmill/tool/builders.h"

using namespace dexelmill;

namespace {

constexpr double kEps = 1e-9;
const Vec3 kZ(0, 0, 1);

/// The interval of the world line through `origin` along `dir`, as coordinates along `dir`
/// measured from the origin.
Interval along(const MoveSweep& s, const Vec3& origin, const Vec3& dir) { return s.intersect(Line{origin, dir}); }

void requireInterval(const Interval& got, double lo, double hi) {
    INFO("got [" << got.lo << ", " << got.hi << "], expected [" << lo << ", " << hi << "]");
    REQUIRE(!got.isEmpty());
    CHECK(got.lo == Approx(lo).margin(kEps));
    CHECK(got.hi == Approx(hi).margin(kEps));
}

/// The hit of the world line through `origin` along `dir` with a sweep of a convex tool.
LineHit hitAlong(const MoveSweep& s, const Vec3& origin, const Vec3& dir) {
    LineHit hits[MoveSweep::kMaxParts];
    REQUIRE(s.intersectParts(Line{origin, dir}, hits) == 1);
    REQUIRE(!hits[0].isEmpty());
    return hits[0];
}

/// Checks a unit normal against its expected value (any length; normalised here).
void checkNormal(const Vec3& got, const Vec3& expected) {
    const Vec3 e = glm::normalize(expected);
    INFO("normal (" << got.x << ", " << got.y << ", " << got.z << "), expected (" << e.x << ", " << e.y << ", "
                    << e.z << ")");
    CHECK(glm::length(got - e) <= kEps);
}

/// Checks both ends of a hit: its interval, its normals, and that neither end is sharp.
void checkSmooth(const LineHit& hit, double lo, double hi, const Vec3& normalLo, const Vec3& normalHi) {
    requireInterval(hit.range, lo, hi);
    checkNormal(hit.normalLo, normalLo);
    checkNormal(hit.normalHi, normalHi);
    CHECK(!hit.sharpLo);
    CHECK(!hit.sharpHi);
}

}  // namespace

TEST_CASE("sweep: flat end mill on a horizontal move", "[sweep]") {
    const Tool flat = flatEndMill(6.0, {20.0, 20.0});
    const MoveSweep s(flat, Vec3(0, 0, 0), Vec3(10, 0, 0), kZ);
    CHECK(s.kind() == SweepKind::Horizontal);
    // A z dexel over the slot: the floor (bottom face) to the top face.
    requireInterval(along(s, Vec3(5, 1, -100), kZ), 100.0, 120.0);
    // A y dexel past the end: the end tool's disk of radius 3 at x = 10, |y| <= sqrt(9 - 4).
    requireInterval(along(s, Vec3(12, -100, 5), Vec3(0, 1, 0)), 100.0 - std::sqrt(5.0), 100.0 + std::sqrt(5.0));
    // A z dexel beside the slot misses.
    CHECK(along(s, Vec3(5, 3.5, -100), kZ).isEmpty());
    // The box: [-3, 13] x [-3, 3] x [0, 20].
    CHECK(s.bounds().lo.x == Approx(-3.0));
    CHECK(s.bounds().hi.x == Approx(13.0));
    CHECK(s.bounds().lo.y == Approx(-3.0));
    CHECK(s.bounds().hi.y == Approx(3.0));
    CHECK(s.bounds().lo.z == Approx(0.0).margin(kEps));
    CHECK(s.bounds().hi.z == Approx(20.0));
}

TEST_CASE("sweep: dexel parallel to the move stretches the static interval", "[sweep]") {
    // Horizontal: the x dexel at y = 1 in the slot: |x| <= sqrt(8) at the start, stretched by 10.
    const Tool flat = flatEndMill(6.0, {20.0, 20.0});
    const MoveSweep h(flat, Vec3(0, 0, 0), Vec3(10, 0, 0), kZ);
    requireInterval(along(h, Vec3(-100, 1, 5), Vec3(1, 0, 0)), 100.0 - std::sqrt(8.0), 110.0 + std::sqrt(8.0));
    // Diagonal: a ball D6 moving 10 along (1, 1, 1)/sqrt(3). The line along the move through the
    // ball centre (0, 0, 3) leaves the ball 3 below it, and the cylinder rho <= 3 where
    // t sqrt(2/3) = 3 above it; the move stretches the upper end by 10.
    const Tool ball = ballEndMill(6.0, {20.0, 20.0});
    const Vec3 dir = glm::normalize(Vec3(1, 1, 1));
    const MoveSweep d(ball, Vec3(0, 0, 0), 10.0 * dir, kZ);
    requireInterval(along(d, Vec3(0, 0, 3), dir), -3.0, 3.0 * std::sqrt(1.5) + 10.0);
    requireInterval(along(d, Vec3(0, 0, 3), -dir), -3.0 * std::sqrt(1.5) - 10.0, 3.0);
}

TEST_CASE("sweep: plunge and retract along the axis", "[sweep]") {
    const Tool flat = flatEndMill(6.0, {20.0, 20.0});
    for (bool plunge : {true, false}) {
        const Vec3 a(0, 0, 10), b(0, 0, 0);
        const MoveSweep s(flat, plunge ? a : b, plunge ? b : a, kZ);
        CHECK(s.kind() == SweepKind::Plunge);
        // A z dexel in the hole: from the lowest tip (0) to the highest top (30).
        requireInterval(along(s, Vec3(1, 1, -100), kZ), 100.0, 130.0);
        // An x dexel at z = 25: only the upper pose reaches it, |x| <= 3.
        requireInterval(along(s, Vec3(-100, 0, 25), Vec3(1, 0, 0)), 97.0, 103.0);
    }
    // Ball D6 plunging 10: a z dexel 2 off the axis starts where the lowest ball has radius 2,
    // z = 3 - sqrt(9 - 4).
    const Tool ball = ballEndMill(6.0, {20.0, 20.0});
    const MoveSweep s(ball, Vec3(0, 0, 10), Vec3(0, 0, 0), kZ);
    requireInterval(along(s, Vec3(0, 2, -100), kZ), 100.0 + 3.0 - std::sqrt(5.0), 130.0);
}

TEST_CASE("sweep: ball end mill ramp, the floor is the grazing capsule", "[sweep]") {
    // Ball D6 from (0,0,0) to (10,0,-5). The centre runs on c(u) = (10u, 0, 3 - 5u). The z
    // dexel at (5, 1) leaves the cylinder of radius 3 about that path where
    // (z - 3)^2 - (13 - z)^2 / 5 + 26 = 9, i.e. 4 z^2 - 4 z - 39 = 0: z = 1/2 - sqrt(10), at
    // u = (13 - z) / 25 in [0, 1], below the centre (the ball's lower half). The top: the top face
    // z = 20 - 5u covers (5, 1) for |5 - 10u| <= sqrt(8), highest at u = 1/2 - sqrt(8)/10.
    const Tool ball = ballEndMill(6.0, {20.0, 20.0});
    const MoveSweep s(ball, Vec3(0, 0, 0), Vec3(10, 0, -5), kZ);
    CHECK(s.kind() == SweepKind::General);
    requireInterval(along(s, Vec3(5, 1, -100), kZ), 100.0 + 0.5 - std::sqrt(10.0), 100.0 + 17.5 + std::sqrt(8.0) / 2);
}

TEST_CASE("sweep: flat end mill ramp, the floor is the swept bottom rim", "[sweep]") {
    // Flat D6 from (0,0,0) to (10,0,-5): the bottom disk at height -5u centred at (10u, 0) covers
    // (5, 1) for u in [1/2 - sqrt(8)/10, 1/2 + sqrt(8)/10]. Only the rim's elliptic-cylinder sweep
    // gives the floor: z = -5 (1/2 + sqrt(8)/10).
    const Tool flat = flatEndMill(6.0, {20.0, 20.0});
    const MoveSweep s(flat, Vec3(0, 0, 0), Vec3(10, 0, -5), kZ);
    requireInterval(along(s, Vec3(5, 1, -100), kZ), 100.0 - 2.5 - std::sqrt(8.0) / 2,
                    100.0 + 17.5 + std::sqrt(8.0) / 2);
    // Ascending, the same move reversed: the same set.
    const MoveSweep r(flat, Vec3(10, 0, -5), Vec3(0, 0, 0), kZ);
    requireInterval(along(r, Vec3(5, 1, -100), kZ), 100.0 - 2.5 - std::sqrt(8.0) / 2,
                    100.0 + 17.5 + std::sqrt(8.0) / 2);
}

TEST_CASE("sweep: bull-nose ramp along a z dexel through the path", "[sweep]") {
    // Bull-nose D10 R2 (flat bottom radius 3, torus rc = 3, rho = 2, zc = 2) from (0,0,0) to
    // (20,0,-4). The z dexel at (10, 0) is |10 - 20u| from the axis at pose u. Poses with
    // |10 - 20u| <= 3 hold their flat bottom over it, the lowest at u = 13/20: z = -2.6. Poses
    // with s = 20u - 13 in [0, 2] hold the torus over it, at z(s) = 2 - sqrt(4 - s^2)
    // - 4 (13 + s) / 20, smallest where s / sqrt(4 - s^2) = 1/5: s = 2 / sqrt(26).
    const Tool bull = bullNoseEndMill(10.0, 2.0, {20.0, 20.0});
    const MoveSweep s(bull, Vec3(0, 0, 0), Vec3(20, 0, -4), kZ);
    const double sOpt = 2.0 / std::sqrt(26.0);
    const double floorZ = 2.0 - std::sqrt(4.0 - sOpt * sOpt) - 4.0 * (13.0 + sOpt) / 20.0;
    const Interval iv = along(s, Vec3(10, 0, -100), kZ);
    REQUIRE(!iv.isEmpty());
    CHECK(iv.lo == Approx(100.0 + floorZ).margin(kEps));
    CHECK(floorZ < -4.0 * 13.0 / 20.0);  // the torus goes deeper than the flat bottom here
    // The top: the top face (height 20 above the tip, radius 5) is over the dexel from u = 1/4,
    // where the tip has come down by 1.
    CHECK(iv.hi == Approx(100.0 + 19.0).margin(kEps));
}

TEST_CASE("sweep: zero-length move is the static tool", "[sweep]") {
    const Tool flat = flatEndMill(6.0, {20.0, 20.0});
    for (const Vec3& end : {Vec3(0.0), Vec3(1e-12, 0, 0)}) {
        const MoveSweep s(flat, Vec3(0.0), end, kZ);
        CHECK(s.kind() == SweepKind::Static);
        requireInterval(along(s, Vec3(1, -100, 5), Vec3(0, 1, 0)), 100.0 - std::sqrt(8.0), 100.0 + std::sqrt(8.0));
        CHECK(along(s, Vec3(1, -100, 21), Vec3(0, 1, 0)).isEmpty());
    }
}

TEST_CASE("sweep: dexel parallel to a tilted tool axis", "[sweep]") {
    // Axis tilted 30 degrees in the x-z plane, move along y (perpendicular to the axis). Lines
    // along the axis through the swept axis, and 1 mm from it across the feed, run the full tool
    // height, from the tip plane to the top plane; one 4 mm from it (past the radius 3) misses.
    const Tool flat = flatEndMill(6.0, {20.0, 20.0});
    const Vec3 n(0.5, 0.0, std::sqrt(3.0) / 2);
    const MoveSweep s(flat, Vec3(0, 0, 0), Vec3(0, 10, 0), n);
    CHECK(s.kind() == SweepKind::Horizontal);
    requireInterval(along(s, Vec3(0, 4, 0) - 50.0 * n, n), 50.0, 70.0);
    requireInterval(along(s, Vec3(0, 4, 0) + 50.0 * n, -n), 30.0, 50.0);
    const Vec3 across(std::sqrt(3.0) / 2, 0.0, -0.5);  // perpendicular to n and to the feed
    requireInterval(along(s, Vec3(0, 4, 0) + across - 50.0 * n, n), 50.0, 70.0);
    CHECK(along(s, Vec3(0, 4, 0) + 4.0 * across - 50.0 * n, n).isEmpty());
    // The box in x: the top face's centre at x = 10 plus 3 cos(30 deg).
    CHECK(s.bounds().hi.x == Approx(10.0 + 3.0 * std::sqrt(3.0) / 2));
    CHECK(s.bounds().lo.x == Approx(-3.0 * std::sqrt(3.0) / 2));
}

TEST_CASE("sweep: a tilted bull nose as wide as a tool may be is swept to a 1e-7 mm", "[sweep]") {
    // kMaxToolSizeMm bounds the tools the sweep is given because its rounding grows with the
    // square of the tool's size: at the cap it must still place the surface within kAtTheCap.
    // A bull nose of that diameter, corner radius r, R = d/2 - r from its axis to the corner's
    // centre, its axis a in the x-z plane tilted by up to 0.6 rad, moves along y across the plane
    // y = 0. There the swept volume's section is the tool's meridian section: its sections a
    // distance off the axis lie inside it, moved toward the axis. Near the corner on the side s
    // (s . a = 0), that section is the points within r of Q = { v <= R, w >= r }, in
    // w = (p - tip) . a, the height above the tip, and v = (p - tip) . s.
    constexpr double kAtTheCap = 1e-7;  // mm: the stock keeps dexel ends 8e-6 mm apart at 100 mm
    constexpr double r = 2.0, h = 200.0;
    const double R = kMaxToolSizeMm / 2 - r;
    const Tool bull = bullNoseEndMill(kMaxToolSizeMm, r, {h, h});
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    int checked = 0;
    for (int pose = 0; pose < 8; ++pose) {
        const double tilt = 0.6 * unit(rng);
        const Vec3 a(std::sin(tilt), 0.0, std::cos(tilt)), s(-std::cos(tilt), 0.0, std::sin(tilt));
        const Vec3 corner(10.0, 0.0, -1.0);  // the corner circle's centre: v = R, w = r
        const Vec3 tip = corner - r * a - R * s;
        const MoveSweep sweep(bull, tip - Vec3(0, 50, 0), tip + Vec3(0, 60, 0), a);
        for (int k = 0; k < 400; ++k) {
            const double turn = M_PI * unit(rng);
            const Vec3 dir(std::cos(turn), 0.0, std::sin(turn));
            const Vec3 origin = corner + Vec3(3.0 * unit(rng), 0.0, 3.0 * unit(rng));
            // Along the line, v = v0 + vd t and w = w0 + wd t. The section holds the half-planes'
            // w >= 0 and v <= R + r but for the square's corner beyond the quarter disk, where an
            // end moves to the line's crossing with the circle (v - R)^2 + (w - r)^2 = r^2.
            const double v0 = glm::dot(origin - tip, s), vd = glm::dot(dir, s);
            const double w0 = glm::dot(origin - tip, a), wd = glm::dot(dir, a);
            const auto upTo = [](double c0, double c1) {  // { t : c0 + c1 t <= 0 }
                if (c1 == 0.0) return c0 <= 0.0 ? Interval::all() : Interval::empty();
                const double t = -c0 / c1;
                return c1 > 0.0 ? Interval{-INFINITY, t} : Interval{t, INFINITY};
            };
            Interval want = upTo(-w0, -wd).intersect(upTo(v0 - R - r, vd));
            const auto cornerOff = [&](double t) {  // beyond Q in v and in w: (v - R, r - w), both > 0
                return std::pair<double, double>{v0 + vd * t - R, r - (w0 + wd * t)};
            };
            const auto outsideDisk = [&](double t) {
                const auto [dv, dw] = cornerOff(t);
                return dv > 0.0 && dw > 0.0 && dv * dv + dw * dw > r * r;
            };
            const double b = (v0 - R) * vd + (w0 - r) * wd, c = (v0 - R) * (v0 - R) + (w0 - r) * (w0 - r) - r * r;
            const double disc = b * b - c;
            if (outsideDisk(want.lo)) want.lo = disc >= 0.0 ? -b - std::sqrt(disc) : INFINITY;
            if (outsideDisk(want.hi)) want.hi = disc >= 0.0 ? -b + std::sqrt(disc) : -INFINITY;
            // Lines that reach the far side of the tool or its top, and those that barely touch.
            if (want.isEmpty() || want.length() > 50.0 || want.length() < 0.1) continue;
            // The boundary's outward normal at an end: from Q's nearest point.
            const auto across = [&](double t) {
                const auto [dv, dw] = cornerOff(t);
                const double nv = std::max(dv, 0.0), nw = std::max(dw, 0.0);
                return std::abs(glm::dot(nv * s - nw * a, dir)) / std::hypot(nv, nw);
            };
            const double acrossLo = across(want.lo), acrossHi = across(want.hi);
            // An end the line crosses at a grazing angle moves far along it for a small error.
            if (acrossLo < 0.05 || acrossHi < 0.05) continue;
            const Interval got = sweep.intersect(Line{origin, dir});
            INFO("tilt " << tilt << ", line from (" << origin.x << ", " << origin.z << ") at " << turn << " rad");
            REQUIRE_FALSE(got.isEmpty());
            // Each end's distance from the section's boundary, across it.
            CHECK(std::abs(got.lo - want.lo) * acrossLo <= kAtTheCap);
            CHECK(std::abs(got.hi - want.hi) * acrossHi <= kAtTheCap);
            ++checked;
        }
    }
    CHECK(checked > 1000);
}

TEST_CASE("sweep: dexel lying in a flat face (closed convention)", "[sweep]") {
    // A horizontal move whose bottom face lies exactly in a dexel's plane: the face's points count
    // as removed. The stadium swept by the flat end mill's bottom disk is |y| <= 3 over the path.
    const Tool flat = flatEndMill(6.0, {20.0, 20.0});
    const MoveSweep s(flat, Vec3(0, 0, 0), Vec3(10, 0, 0), kZ);
    requireInterval(along(s, Vec3(5, -100, 0), Vec3(0, 1, 0)), 97.0, 103.0);
    requireInterval(along(s, Vec3(-100, 0, 0), Vec3(1, 0, 0)), 97.0, 113.0);
    requireInterval(along(s, Vec3(5, -100, 20), Vec3(0, 1, 0)), 97.0, 103.0);  // the top face
    // A bull-nose's bottom face has the torus's inner radius: D10 R2 -> |y| <= 3.
    const Tool bull = bullNoseEndMill(10.0, 2.0, {20.0, 20.0});
    const MoveSweep b(bull, Vec3(0, 0, 0), Vec3(10, 0, 0), kZ);
    requireInterval(along(b, Vec3(5, -100, 0), Vec3(0, 1, 0)), 97.0, 103.0);
    // Just below the face nothing is removed.
    CHECK(along(b, Vec3(5, -100, -1e-6), Vec3(0, 1, 0)).isEmpty());
}

TEST_CASE("sweep: a non-convex tool is swept part by part", "[sweep]") {
    // Radius 3 on [0, 4], 1.5 on [4, 12], 4 on [12, 20]: a z dexel 2 from the path passes the
    // narrow neck, so it gets the bottom and top parts only.
    const Tool stepped("stepped", {ConePiece{0, 4, 3, 3}, ConePiece{4, 12, 1.5, 1.5}, ConePiece{12, 20, 4, 4}}, 20);
    const MoveSweep s(stepped, Vec3(0, 0, 0), Vec3(10, 0, -1), kZ);
    REQUIRE(s.partCount() == 3);
    const std::vector<Interval> all = s.intersectAll(Line{Vec3(5, 2, -100), kZ});
    REQUIRE(all.size() == 2);
    // The bottom part's floor: its bottom disk (radius 3, at height -u) covers (5, 2) for
    // |5 - 10u| <= sqrt(5); the lowest at u = 1/2 + sqrt(5)/10. Its top: height 4 - u at the
    // smallest u. The top part: radius 4, |5 - 10u| <= sqrt(12), heights 12 - u .. 20 - u.
    CHECK(all[0].lo == Approx(100.0 - 0.5 - std::sqrt(5.0) / 10).margin(kEps));
    CHECK(all[0].hi == Approx(100.0 + 4.0 - 0.5 + std::sqrt(5.0) / 10).margin(kEps));
    CHECK(all[1].lo == Approx(100.0 + 12.0 - 0.5 - std::sqrt(12.0) / 10).margin(kEps));
    CHECK(all[1].hi == Approx(100.0 + 20.0 - 0.5 + std::sqrt(12.0) / 10).margin(kEps));
    // intersect() is the hull.
    const Interval hull = s.intersect(Line{Vec3(5, 2, -100), kZ});
    CHECK(hull.lo == Approx(all[0].lo));
    CHECK(hull.hi == Approx(all[1].hi));
}

TEST_CASE("sweep: shank region is swept on its own", "[sweep]") {
    // Flat D6 with cutting length 12 of 20: the shank region [12, 20] swept horizontally covers a
    // z dexel in the slot from 12 to 20 only.
    const Tool flat = flatEndMill(6.0, {12.0, 20.0});
    const MoveSweep shank(flat.region(12.0, 20.0), Vec3(0, 0, 0), Vec3(10, 0, 0), kZ);
    const MoveSweep cutting(flat.region(0.0, 12.0), Vec3(0, 0, 0), Vec3(10, 0, 0), kZ);
    requireInterval(along(shank, Vec3(5, 0, -100), kZ), 112.0, 120.0);
    requireInterval(along(cutting, Vec3(5, 0, -100), kZ), 100.0, 112.0);
    CHECK(shank.bounds().lo.z == Approx(12.0));
}

TEST_CASE("sweep: bad input throws dexelmill::Error", "[sweep]") {
    const Tool flat = flatEndMill(6.0);
    CHECK_THROWS_AS(MoveSweep(flat, Vec3(0.0), Vec3(1, 0, 0), Vec3(0.0)), Error);
    std::vector<ProfilePiece> many;
    for (int i = 0; i < 10; ++i)  // alternating radii: ten convex parts
        many.push_back(ConePiece{double(i), double(i + 1), i % 2 ? 1.0 : 2.0, i % 2 ? 1.0 : 2.0});
    const Tool comb("comb", many, 10.0);
    CHECK_THROWS_AS(MoveSweep(comb, Vec3(0.0), Vec3(1, 0, 0), kZ), Error);
}

TEST_CASE("sweep: the box holds the swept tool and touches it", "[sweep]") {
    // Random poses along random moves of a tilted bull-nose: every sampled surface point lies in
    // the box, and each face of the box is reached to within the sampling resolution.
    const Tool bull = bullNoseEndMill(8.0, 2.0, {15.0, 25.0});
    const Vec3 n = glm::normalize(Vec3(0.3, -0.2, 1.0));
    const Vec3 a(1, 2, 3), b(11, -4, 0);
    const MoveSweep s(bull, a, b, n);
    Vec3 d1, d2;
    ToolFrame::perpendicularPair(n, d1, d2);
    Box seen;
    for (int iu = 0; iu <= 20; ++iu) {
        const Vec3 tip = a + (b - a) * (iu / 20.0);
        for (int iz = 0; iz <= 500; ++iz) {
            const double z = 25.0 * iz / 500.0;
            const double r = bull.radiusAt(z);
            for (int k = 0; k < 720; ++k) {
                const double phi = 2 * M_PI * k / 720.0;
                seen.expand(tip + z * n + r * (std::cos(phi) * d1 + std::sin(phi) * d2));
            }
        }
    }
    for (int i = 0; i < 3; ++i) {
        CHECK(s.bounds().lo[i] <= seen.lo[i] + 1e-12);
        CHECK(s.bounds().hi[i] >= seen.hi[i] - 1e-12);
        CHECK(s.bounds().lo[i] == Approx(seen.lo[i]).margin(1e-3));
        CHECK(s.bounds().hi[i] == Approx(seen.hi[i]).margin(1e-3));
    }
}

TEST_CASE("sweep: the cheap bound holds every line's interval", "[sweep]") {
    // bound() may only be wider than intersect() (which the oracle tests check): over random
    // lines, each axis family and random directions, for every kind of move.
    const Tool tools[] = {flatEndMill(6.0, {15.0, 25.0}), ballEndMill(6.0, {15.0, 25.0}),
                          bullNoseEndMill(8.0, 2.0, {15.0, 25.0})};
    const Vec3 tilted = glm::normalize(Vec3(0.3, -0.2, 1.0));
    const struct {
        Vec3 end, axis;
    } moves[] = {{Vec3(10, 4, 0), kZ}, {Vec3(10, 4, -3), kZ}, {Vec3(0, 0, -5), kZ}, {Vec3(0, 0, 0), kZ},
                 {Vec3(10, 4, -3), tilted}, {Vec3(0.4, 0, 0.1), kZ}};
    std::uint64_t state = 12345;
    auto uniform = [&state](double lo, double hi) {
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        return lo + (hi - lo) * double(state >> 11) * 0x1.0p-53;
    };
    for (const Tool& tool : tools) {
        for (const auto& mv : moves) {
            const MoveSweep s(tool, Vec3(1, 2, 3), Vec3(1, 2, 3) + mv.end, mv.axis);
            int hits = 0, cornered = 0;
            for (int i = 0; i < 3000; ++i) {
                Vec3 dir(0.0);
                if (i % 4 == 3) dir = glm::normalize(Vec3(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)));
                else dir[i % 4] = 1.0;
                const Vec3 origin(uniform(-8, 16), uniform(-6, 12), uniform(-6, 12));
                const Line line{origin - 50.0 * dir, dir};
                const Interval exact = s.intersect(line), cheap = s.bound(line);
                // The world-frame boxes (bound(Line)) and the move frame's (bound(LocalLine)) are
                // the same slabs, up to rounding.
                const Interval framed = s.bound(s.toLocal(line));
                INFO(tool.description() << " line " << i);
                REQUIRE(cheap.isEmpty() == framed.isEmpty());
                if (!cheap.isEmpty()) {
                    CHECK(std::abs(cheap.lo - framed.lo) <= 1e-10);
                    CHECK(std::abs(cheap.hi - framed.hi) <= 1e-10);
                }
                // The narrowed bound lies within the boxes' and still holds the interval.
                const Interval narrow = s.narrowBound(line);
                if (!narrow.isEmpty()) {
                    REQUIRE(!cheap.isEmpty());
                    CHECK(narrow.lo >= cheap.lo);
                    CHECK(narrow.hi <= cheap.hi);
                } else if (!cheap.isEmpty() && exact.isEmpty()) {
                    ++cornered;
                }
                // Given the boxes' range, or the whole line, it narrows that without the boxes.
                const Interval given = cheap.isEmpty() ? cheap : s.narrowBound(line, cheap);
                const Interval whole = s.narrowBound(line, Interval::all());
                if (!given.isEmpty()) {
                    CHECK(given.lo >= cheap.lo);
                    CHECK(given.hi <= cheap.hi);
                }
                if (exact.isEmpty()) continue;
                ++hits;
                REQUIRE(!cheap.isEmpty());
                CHECK(cheap.lo <= exact.lo);
                CHECK(cheap.hi >= exact.hi);
                for (const Interval& n : {narrow, given, whole}) {
                    REQUIRE(!n.isEmpty());
                    CHECK(n.lo <= exact.lo);
                    CHECK(n.hi >= exact.hi);
                }
            }
            CHECK(hits > 200);
            // Lines that pass a box beside the tool: the narrowed bound turns some of them away.
            CHECK(cornered > 20);
        }
    }
    // Along the axis the bound is the profile's own height over the swept axis's nearest point: a
    // ball (radius 3) moving horizontally, a z line 2 mm beside its path is inside from
    // z = 3 - sqrt(9 - 4) above the tip, exactly where the sweep starts.
    const MoveSweep ball(ballEndMill(6.0, {15.0, 25.0}), Vec3(0, 0, 0), Vec3(10, 0, 0), kZ);
    const Interval cheap = ball.bound(Line{Vec3(5, 2, -10), kZ});
    CHECK(cheap.lo == Approx(10 + 3 - std::sqrt(5.0)).margin(1e-8));
}

TEST_CASE("sweep: the narrowed bound turns away lines beside the tool in its box", "[sweep]") {
    // A flat D10 x 20 with its tip at the origin, on each kind of move: lines through a corner of
    // the box across the axis miss the tool, which the box's bound cannot tell.
    const Tool tool = flatEndMill(10.0, {20.0, 20.0});
    const struct {
        const char* name;
        Vec3 end;
    } moves[] = {{"static", Vec3(0.0)}, {"plunge", Vec3(0, 0, -2)}, {"horizontal", Vec3(0, 0.5, 0)},
                 {"ramp", Vec3(0, 0.5, -0.2)}};
    for (const auto& mv : moves) {
        INFO(mv.name);
        const MoveSweep s(tool, Vec3(0.0), mv.end, kZ);
        // Along z tilted a little at (4.4, -4.5): inside the box's square about the disk of
        // radius 5, 6.3 from the axis. (A line along the axis itself has a narrower bound already.)
        const Line steep{Vec3(4.4, -4.5, -10.0), glm::normalize(Vec3(0.001, 0.0, 1.0))};
        CHECK_FALSE(s.bound(steep).isEmpty());
        CHECK(s.narrowBound(steep).isEmpty());
        // Along x 5.2 mm beside the tip's path, at the tool's heights; at 4.9 mm, through it.
        const Line beside{Vec3(-20.0, -5.2, 3.0), Vec3(1, 0, 0)};
        CHECK(s.narrowBound(beside).isEmpty());
        const Line through{Vec3(-20.0, 4.9, 3.0), Vec3(1, 0, 0)};
        const Interval exact = s.intersect(through), narrow = s.narrowBound(through);
        REQUIRE(!exact.isEmpty());
        CHECK(narrow.lo <= exact.lo);
        CHECK(narrow.hi >= exact.hi);
        // A horizontal line below the tip's lowest height meets nothing.
        const Line below{Vec3(-20.0, 0.0, std::min(0.0, mv.end.z) - 0.01), Vec3(1, 0, 0)};
        CHECK(s.narrowBound(below).isEmpty());
        // Oblique through the tool: the bound holds its interval.
        const Line oblique{Vec3(-22.0, 1.0, -20.0), glm::normalize(Vec3(1, 0, 1))};
        const Interval oe = s.intersect(oblique), on = s.narrowBound(oblique);
        REQUIRE(!oe.isEmpty());
        CHECK(on.lo <= oe.lo);
        CHECK(on.hi >= oe.hi);
    }
}

// Hermite data: the swept volume's outward unit normal at both ends of a line's interval. Each
// expected normal is derived in the comments from the geometry of the case.

TEST_CASE("sweep normals: flat end mill on a horizontal move, floor, top and walls", "[sweep]") {
    const Tool flat = flatEndMill(6.0, {20.0, 20.0});
    const MoveSweep s(flat, Vec3(0, 0, 0), Vec3(10, 0, 0), kZ);
    // A z dexel in the slot enters through the floor (the bottom faces, normal -z) and leaves
    // through the top faces (+z).
    checkSmooth(hitAlong(s, Vec3(5, 1, -100), kZ), 100.0, 120.0, -kZ, kZ);
    // A y dexel across the slot: the walls are the cylinder's grazing generators at y = -+3.
    checkSmooth(hitAlong(s, Vec3(5, -100, 5), Vec3(0, 1, 0)), 97.0, 103.0, Vec3(0, -1, 0), Vec3(0, 1, 0));
    // A y dexel past the end meets only the end tool, at (12, -+sqrt(5)): the cylinder's normal
    // points away from its axis at x = 10.
    checkSmooth(hitAlong(s, Vec3(12, -100, 5), Vec3(0, 1, 0)), 100.0 - std::sqrt(5.0), 100.0 + std::sqrt(5.0),
                Vec3(2, -std::sqrt(5.0), 0), Vec3(2, std::sqrt(5.0), 0));
    // An x dexel along the move at y = 1 enters the start tool at x = -sqrt(8) and leaves the end
    // tool at x = 10 + sqrt(8).
    checkSmooth(hitAlong(s, Vec3(-100, 1, 5), Vec3(1, 0, 0)), 100.0 - std::sqrt(8.0), 110.0 + std::sqrt(8.0),
                Vec3(-std::sqrt(8.0), 1, 0), Vec3(std::sqrt(8.0), 1, 0));
}

TEST_CASE("sweep normals: ball end mill ramp, the capsule", "[sweep]") {
    // Ball D6 from (0,0,0) to (10,0,-5) (the interval case above): the z dexel at (5, 1) leaves
    // the capsule at z = 1/2 - sqrt(10), at u = (13 - z) / 25, where the ball's centre is
    // c(u) = (10u, 0, 3 - 5u); the normal points from c(u) to the point.
    const Tool ball = ballEndMill(6.0, {20.0, 20.0});
    const MoveSweep s(ball, Vec3(0, 0, 0), Vec3(10, 0, -5), kZ);
    const double z = 0.5 - std::sqrt(10.0), u = (13.0 - z) / 25.0;
    const Vec3 floorNormal = Vec3(5, 1, z) - Vec3(10 * u, 0, 3 - 5 * u);
    CHECK(glm::length(floorNormal) == Approx(3.0));
    CHECK(glm::dot(floorNormal, Vec3(10, 0, -5)) == Approx(0.0).margin(1e-12));  // grazing
    // The top is the swept rim of the top face (radius 3): near (5, 1) it is z = 20 - 5 u(x, y)
    // with u the first pose covering (x, y), u = (x - sqrt(9 - y^2)) / 10, so
    // z = 20 - (x - sqrt(9 - y^2)) / 2 and the upward normal (-z_x, -z_y, 1) is
    // (1/2, y / (2 sqrt(9 - y^2)), 1), at y = 1 proportional to (sqrt(8), 1, 2 sqrt(8)).
    const Vec3 topNormal(std::sqrt(8.0), 1.0, 2.0 * std::sqrt(8.0));
    checkSmooth(hitAlong(s, Vec3(5, 1, -100), kZ), 100.0 + z, 100.0 + 17.5 + std::sqrt(8.0) / 2, floorNormal,
                topNormal);
}

TEST_CASE("sweep normals: flat end mill ramp, the swept bottom rim", "[sweep]") {
    // Flat D6 from (0,0,0) to (10,0,-5). Near (5, 1) the floor is z(x, y) = -5 u(x, y) with u the
    // last pose whose bottom disk covers (x, y): (x - 10u)^2 + y^2 = 9, u = (x + sqrt(9 - y^2)) / 10,
    // so z = -(x + sqrt(9 - y^2)) / 2. The outward (downward) normal is (z_x, z_y, -1) =
    // (-1/2, y / (2 sqrt(9 - y^2)), -1), at y = 1 proportional to (-sqrt(8), 1, -2 sqrt(8)). The
    // top is the top rim's sweep, mirrored (see the ball ramp): (sqrt(8), 1, 2 sqrt(8)).
    const Tool flat = flatEndMill(6.0, {20.0, 20.0});
    const Vec3 floorNormal(-std::sqrt(8.0), 1.0, -2.0 * std::sqrt(8.0));
    const Vec3 topNormal(std::sqrt(8.0), 1.0, 2.0 * std::sqrt(8.0));
    const MoveSweep s(flat, Vec3(0, 0, 0), Vec3(10, 0, -5), kZ);
    checkSmooth(hitAlong(s, Vec3(5, 1, -100), kZ), 100.0 - 2.5 - std::sqrt(8.0) / 2,
                100.0 + 17.5 + std::sqrt(8.0) / 2, floorNormal, topNormal);
    // Ascending, the same move reversed: the same set, the same normals.
    const MoveSweep r(flat, Vec3(10, 0, -5), Vec3(0, 0, 0), kZ);
    checkSmooth(hitAlong(r, Vec3(5, 1, -100), kZ), 100.0 - 2.5 - std::sqrt(8.0) / 2,
                100.0 + 17.5 + std::sqrt(8.0) / 2, floorNormal, topNormal);
}

TEST_CASE("sweep normals: bull-nose ramp, the torus", "[sweep]") {
    // Bull-nose D10 R2 from (0,0,0) to (20,0,-4) (the interval case above): the z dexel at (10, 0)
    // leaves through the torus of the pose whose axis is 3 + s ahead of it, s = 2 / sqrt(26), at the
    // point of the profile circle (centre 3 from the axis, 2 up) that is s further out: the normal
    // is (-s, 0, -sqrt(4 - s^2)) / 2 (ahead of the dexel is +x, so outward is -x), and it is
    // perpendicular to the feed: -20 s + 4 sqrt(4 - s^2) = 0 is the optimum's condition. The top:
    // the top rim's sweep (radius 5), z = 20 - 4 u(x, y) with u = (x - sqrt(25 - y^2)) / 20, whose
    // upward normal (-z_x, -z_y, 1) is (1/5, 0, 1) at y = 0.
    const Tool bull = bullNoseEndMill(10.0, 2.0, {20.0, 20.0});
    const MoveSweep s(bull, Vec3(0, 0, 0), Vec3(20, 0, -4), kZ);
    const double sOpt = 2.0 / std::sqrt(26.0);
    const double floorZ = 2.0 - std::sqrt(4.0 - sOpt * sOpt) - 4.0 * (13.0 + sOpt) / 20.0;
    checkSmooth(hitAlong(s, Vec3(10, 0, -100), kZ), 100.0 + floorZ, 119.0, Vec3(-sOpt, 0, -std::sqrt(4 - sOpt * sOpt)),
                Vec3(1, 0, 5));
}

TEST_CASE("sweep normals: plunge, the shadow cylinder is radial", "[sweep]") {
    const Tool flat = flatEndMill(6.0, {20.0, 20.0});
    for (bool plunge : {true, false}) {
        const Vec3 a(0, 0, 10), b(0, 0, 0);
        const MoveSweep s(flat, plunge ? a : b, plunge ? b : a, kZ);
        // An x dexel at y = 1, z = 5 crosses the hole's wall at x = -+sqrt(8).
        checkSmooth(hitAlong(s, Vec3(-100, 1, 5), Vec3(1, 0, 0)), 100.0 - std::sqrt(8.0), 100.0 + std::sqrt(8.0),
                    Vec3(-std::sqrt(8.0), 1, 0), Vec3(std::sqrt(8.0), 1, 0));
        // A z dexel in the hole: the lowest pose's bottom face and the highest pose's top face.
        checkSmooth(hitAlong(s, Vec3(1, 1, -100), kZ), 100.0, 130.0, -kZ, kZ);
    }
}

TEST_CASE("sweep normals: tilted tool axis (3+2)", "[sweep]") {
    // Horizontal: a flat D6 on an axis tilted 30 degrees, moving along y. A line along the axis
    // runs from the tip plane (normal -n) to the top plane (+n); a line across the axis and the
    // feed, 5 up the axis, crosses the two walls (normals -+ across).
    const Tool flat = flatEndMill(6.0, {20.0, 20.0});
    const Vec3 n(0.5, 0.0, std::sqrt(3.0) / 2);
    const Vec3 across(std::sqrt(3.0) / 2, 0.0, -0.5);
    const MoveSweep h(flat, Vec3(0, 0, 0), Vec3(0, 10, 0), n);
    checkSmooth(hitAlong(h, Vec3(0, 4, 0) - 50.0 * n, n), 50.0, 70.0, -n, n);
    checkSmooth(hitAlong(h, Vec3(0, 4, 0) + 5.0 * n - 50.0 * across, across), 47.0, 53.0, -across, across);

    // General: a ball D6 on a tilted axis, moving up and sideways. Its centre runs on
    // c(u) = a + 3 n + u f. At c(1/2) the capsule's cross-section is the circle of radius 3 in the
    // plane perpendicular to f. Along e (perpendicular to n and f) nothing else of the tool reaches
    // farther: the line through c(1/2) along e meets the sweep in [-3, 3] around it, normals -+e.
    // Along -q, q the unit vector across f towards n, the shank is above: the line's far end is
    // the capsule's lowest line, c(1/2) - 3 q, with normal -q.
    const Tool ball = ballEndMill(6.0, {20.0, 20.0});
    const Vec3 t = glm::normalize(Vec3(0.3, -0.2, 1.0));
    const Vec3 a(1, 2, 3), f(8, -3, 4);
    const MoveSweep g(ball, a, a + f, t);
    REQUIRE(g.kind() == SweepKind::General);
    const Vec3 centre = a + 3.0 * t + 0.5 * f;
    const Vec3 e = glm::normalize(glm::cross(t, f));
    const Vec3 fu = glm::normalize(f);
    const Vec3 q = glm::normalize(t - glm::dot(t, fu) * fu);
    checkSmooth(hitAlong(g, centre - 50.0 * e, e), 47.0, 53.0, -e, e);
    const LineHit down = hitAlong(g, centre + 50.0 * q, -q);
    CHECK(down.range.hi == Approx(53.0).margin(kEps));
    checkNormal(down.normalHi, -q);
    CHECK(!down.sharpHi);
}

TEST_CASE("sweep normals: the static tool at the ends of a move", "[sweep]") {
    const Tool ball = ballEndMill(6.0, {20.0, 20.0});
    // Horizontal, a line along the move at y = 1, z = 2: it enters the start ball (centre
    // (0, 0, 3)) at (-sqrt(7), 1, 2) and leaves the end ball (centre (10, 0, 3)) at
    // (10 + sqrt(7), 1, 2); the normals point from the centres.
    const MoveSweep h(ball, Vec3(0, 0, 0), Vec3(10, 0, 0), kZ);
    checkSmooth(hitAlong(h, Vec3(-100, 1, 2), Vec3(1, 0, 0)), 100.0 - std::sqrt(7.0), 110.0 + std::sqrt(7.0),
                Vec3(-std::sqrt(7.0), 1, -1), Vec3(std::sqrt(7.0), 1, -1));
    // A ramp from (0,0,0) to (10,0,-5), a z dexel at (-2, 1), behind the start: the start ball
    // covers it from z = 3 - sqrt(9 - 5) = 1 (normal (-2, 1, -2) / 3 from its centre), and the
    // later poses only higher up (the lowest covered height 3 - 5u - sqrt(8 - (2 + 10u)^2) rises
    // at u = 0 with slope 5). The top: the start tool's top face.
    const MoveSweep r(ball, Vec3(0, 0, 0), Vec3(10, 0, -5), kZ);
    checkSmooth(hitAlong(r, Vec3(-2, 1, -100), kZ), 101.0, 120.0, Vec3(-2, 1, -2), kZ);
}

TEST_CASE("sweep normals: ends on a crease are sharp", "[sweep]") {
    const Tool flat = flatEndMill(6.0, {20.0, 20.0});
    const double r2 = std::sqrt(2.0);
    {
        // The tool at rest: a line through its bottom rim at (3, 0, 0), into the tool along
        // (-1, 0, 1): the lower end is on the rim, between the bottom face (-z) and the side (+x);
        // it leaves through the side at x = -3 (6 further along x, at 6 sqrt(2)).
        const MoveSweep s(flat, Vec3(0.0), Vec3(0.0), kZ);
        const Vec3 dir = Vec3(-1, 0, 1) / r2;
        const LineHit hit = hitAlong(s, Vec3(3, 0, 0) - 10.0 * dir, dir);
        requireInterval(hit.range, 10.0, 10.0 + 6.0 * r2);
        CHECK(hit.sharpLo);
        checkNormal(hit.normalLo, Vec3(1, 0, -1));
        CHECK(!hit.sharpHi);
        checkNormal(hit.normalHi, Vec3(-1, 0, 0));
    }
    {
        // A horizontal move and a line lying in the bottom face's plane: it crosses the slot's
        // edges, where the floor meets the walls.
        const MoveSweep s(flat, Vec3(0, 0, 0), Vec3(10, 0, 0), kZ);
        const LineHit hit = hitAlong(s, Vec3(5, -100, 0), Vec3(0, 1, 0));
        requireInterval(hit.range, 97.0, 103.0);
        CHECK(hit.sharpLo);
        CHECK(hit.sharpHi);
        checkNormal(hit.normalLo, Vec3(0, -1, -1));
        checkNormal(hit.normalHi, Vec3(0, 1, -1));
    }
    {
        // A descending ramp: the start tool's bottom rim at its back, (-3, 0, 0), is reached by no
        // later pose. A line through it into the start tool along (1, 0, 1) starts there on the
        // crease between the start tool's bottom face and the swept rim: a normal from that cone
        // has no y part and points back and down.
        const MoveSweep s(flat, Vec3(0, 0, 0), Vec3(10, 0, -5), kZ);
        const Vec3 dir = Vec3(1, 0, 1) / r2;
        const LineHit hit = hitAlong(s, Vec3(-3, 0, 0) - 10.0 * dir, dir);
        CHECK(hit.range.lo == Approx(10.0).margin(kEps));
        CHECK(hit.sharpLo);
        CHECK(glm::length(hit.normalLo) == Approx(1.0));
        CHECK(hit.normalLo.y == Approx(0.0).margin(kEps));
        CHECK(hit.normalLo.x < 0.0);
        CHECK(hit.normalLo.z < 0.0);
    }
    {
        // A V-bit (45 degrees) ramping gently, f = (10, 0, -1): the cone's generators at
        // cos(phi) = -1/10 graze, and the apex's path is a crease of the sweep where their two
        // strips meet. A z dexel through the apex's path at u = 1/2 starts there, at z = -1/2
        // (other poses put the cone, z = -u + |5 - 10u|, higher). The two strips' normals,
        // (-1/10, -+sqrt(0.99), -1) / sqrt(2), tie there: the mean has no y part.
        const Tool vbit = chamferMill(0.0, M_PI / 4, 6.0, {20.0, 20.0});
        const MoveSweep s(vbit, Vec3(0, 0, 0), Vec3(10, 0, -1), kZ);
        const LineHit hit = hitAlong(s, Vec3(5, 0, -100), kZ);
        CHECK(hit.range.lo == Approx(99.5).margin(kEps));
        CHECK(hit.sharpLo);
        checkNormal(hit.normalLo, Vec3(-0.1, 0, -1));
    }
}
