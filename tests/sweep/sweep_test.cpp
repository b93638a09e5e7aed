// The sweep solver on hand-worked cases: one per envelope part and per degenerate case of
// method.md section 5. Expected values are derived in the comments, not taken from the code.
#include <catch2/catch.hpp>

#include <cmath>

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
            int hits = 0;
            for (int i = 0; i < 3000; ++i) {
                Vec3 dir(0.0);
                if (i % 4 == 3) dir = glm::normalize(Vec3(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)));
                else dir[i % 4] = 1.0;
                const Vec3 origin(uniform(-8, 16), uniform(-6, 12), uniform(-6, 12));
                const Line line{origin - 50.0 * dir, dir};
                const Interval exact = s.intersect(line), cheap = s.bound(line);
                if (exact.isEmpty()) continue;
                ++hits;
                INFO(tool.description() << " line " << i);
                REQUIRE(!cheap.isEmpty());
                CHECK(cheap.lo <= exact.lo);
                CHECK(cheap.hi >= exact.hi);
            }
            CHECK(hits > 200);
        }
    }
    // Along the axis the bound is the profile's own height over the swept axis's nearest point: a
    // ball (radius 3) moving horizontally, a z line 2 mm beside its path is inside from
    // z = 3 - sqrt(9 - 4) above the tip, exactly where the sweep starts.
    const MoveSweep ball(ballEndMill(6.0, {15.0, 25.0}), Vec3(0, 0, 0), Vec3(10, 0, 0), kZ);
    const Interval cheap = ball.bound(Line{Vec3(5, 2, -10), kZ});
    CHECK(cheap.lo == Approx(10 + 3 - std::sqrt(5.0)).margin(1e-8));
}
