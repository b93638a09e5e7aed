// How the refinement cuts a triangle whose edges are split: the pieces' angles and facing are
// measured here from their corners, independently of the rule that chose them.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "refine/detail/pieces.h"

using namespace dexelmill;
using detail::Local;

namespace {

/// The angles of the triangle (a, b, c), in degrees.
std::array<double, 3> angles(const Vec3& a, const Vec3& b, const Vec3& c) {
    const std::array<Vec3, 3> p{a, b, c};
    std::array<double, 3> out{};
    for (int k = 0; k < 3; ++k) {
        const Vec3 u = p[std::size_t((k + 1) % 3)] - p[std::size_t(k)];
        const Vec3 v = p[std::size_t((k + 2) % 3)] - p[std::size_t(k)];
        out[std::size_t(k)] =
            std::acos(std::clamp(glm::dot(u, v) / (glm::length(u) * glm::length(v)), -1.0, 1.0)) * 180.0 / M_PI;
    }
    return out;
}

double widestAngle(const Vec3& a, const Vec3& b, const Vec3& c) {
    const std::array<double, 3> t = angles(a, b, c);
    return std::max({t[0], t[1], t[2]});
}

std::array<Vec3, 6> withMidpoints(const Vec3& a, const Vec3& b, const Vec3& c) {
    return {a, b, c, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)};
}

}  // namespace

TEST_CASE("split pieces: a piece whose new corner lies nearly on its far side is refused", "[refine]") {
    // Edge 0 of the triangle (0,0,0), (2,0,0), (0,2,0) split at (0.002, 0.5, 0): the piece
    // (corner 0, new vertex, corner 2) has an angle of 179.8 degrees at the new vertex, which
    // lies 0.002 from the side x = 0. It faces the triangle's way and is no sliver by area (its
    // doubled area is 1e-3 of its longest side squared), but its normal is noise: a split point
    // that far off its midpoint (here in the plane) is refused.
    std::array<Vec3, 6> p = withMidpoints(Vec3(0.0), Vec3(2.0, 0.0, 0.0), Vec3(0.0, 2.0, 0.0));
    p[3] = Vec3(0.002, 0.5, 0.0);
    REQUIRE(widestAngle(p[0], p[3], p[2]) > 179.0);
    std::array<Local, 4> out;
    CHECK(detail::splitPieces(p, 1u, Vec3(0.0, 0.0, 1.0), out) == 0);
    // The same split at the midpoint is made.
    p[3] = Vec3(1.0, 0.0, 0.0);
    CHECK(detail::splitPieces(p, 1u, Vec3(0.0, 0.0, 1.0), out) == 2);
}

TEST_CASE("split pieces: every piece made faces its triangle's way with no angle above 170 degrees", "[refine]") {
    for (const unsigned seed : {1u, 2u, 3u}) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<double> coord(-1.0, 1.0), shift(-0.3, 0.3);
        std::size_t made = 0, refused = 0;
        for (int trial = 0; trial < 4000; ++trial) {
            const Vec3 a(coord(rng), coord(rng), coord(rng)), b(coord(rng), coord(rng), coord(rng)),
                c(coord(rng), coord(rng), coord(rng));
            const Vec3 area = glm::cross(b - a, c - a);
            if (glm::length(area) < 1e-3 || widestAngle(a, b, c) > 150.0) continue;
            const Vec3 n = glm::normalize(area);
            std::array<Vec3, 6> p = withMidpoints(a, b, c);
            const unsigned mask = 1u + unsigned(rng() % 7u);
            // Split points off their midpoints by up to 0.3 of the longest side, in any direction.
            const double side = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
            for (int k = 0; k < 3; ++k)
                if (mask & (1u << k)) p[std::size_t(3 + k)] += side * Vec3(shift(rng), shift(rng), shift(rng));
            std::array<Local, 4> out;
            const int count = detail::splitPieces(p, mask, n, out);
            if (count == 0) {
                ++refused;
                continue;
            }
            ++made;
            const int bits = int(mask & 1u) + int((mask >> 1) & 1u) + int((mask >> 2) & 1u);
            CHECK(count == bits + 1);
            for (int i = 0; i < count; ++i) {
                const Vec3 q0 = p[std::size_t(out[std::size_t(i)][0])], q1 = p[std::size_t(out[std::size_t(i)][1])],
                           q2 = p[std::size_t(out[std::size_t(i)][2])];
                const Vec3 s = glm::cross(q1 - q0, q2 - q0);
                CHECK(glm::dot(s, n) > 0.0);
                CHECK(widestAngle(q0, q1, q2) <= 170.0 + 1e-9);
            }
        }
        INFO("seed " << seed << ": made " << made << ", refused " << refused);
        CHECK(made > 1000);
        CHECK(refused > 0);
    }
}

TEST_CASE("split pieces: splits at the midpoints of a fair triangle are always made", "[refine]") {
    // Halving edges keeps the pieces' angles within the parent's and its medians': a triangle with
    // angles between 30 and 100 degrees has none above 170 after any of the seven splits.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> coord(-1.0, 1.0);
    int tested = 0;
    while (tested < 2000) {
        const Vec3 a(coord(rng), coord(rng), coord(rng)), b(coord(rng), coord(rng), coord(rng)),
            c(coord(rng), coord(rng), coord(rng));
        const std::array<double, 3> t = angles(a, b, c);
        if (glm::length(glm::cross(b - a, c - a)) < 1e-2 || std::max({t[0], t[1], t[2]}) > 100.0 ||
            std::min({t[0], t[1], t[2]}) < 30.0)
            continue;
        ++tested;
        const Vec3 n = glm::normalize(glm::cross(b - a, c - a));
        const std::array<Vec3, 6> p = withMidpoints(a, b, c);
        for (unsigned mask = 1; mask < 8; ++mask) {
            std::array<Local, 4> out;
            CHECK(detail::splitPieces(p, mask, n, out) > 0);
        }
    }
}
