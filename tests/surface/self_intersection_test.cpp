// The tests' self-intersection count (support/self_intersection.h) on meshes whose answer is
// known by construction.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "support/self_intersection.h"
#include "support/uv_sphere.h"

using namespace dexelmill;
using dexelmill::testing::countSelfIntersections;

namespace {

/// `b`'s vertices and triangles appended to `a`'s, moved by `offset`.
Mesh joined(Mesh a, const Mesh& b, const Vec3& offset) {
    const std::uint32_t base = std::uint32_t(a.vertices.size());
    for (const Vec3& v : b.vertices) a.vertices.push_back(v + offset);
    for (const Mesh::Triangle& t : b.triangles)
        a.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    return a;
}

/// Two triangles and the square they make in the plane z = 0, (0, 0) to (1, 1).
Mesh square() {
    Mesh m;
    m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    return m;
}

}  // namespace

TEST_CASE("self-intersections: closed spheres apart have none, overlapping ones do",
          "[surface][oracle]") {
    const Mesh sphere = testing::uvSphere(12, 24, 1.0);
    CHECK(countSelfIntersections(sphere).pairs == 0);
    CHECK(countSelfIntersections(joined(sphere, sphere, Vec3(2.5, 0.0, 0.0))).pairs == 0);
    // Overlapping by half a radius: their surfaces cross along a circle, through many triangles.
    const testing::SelfIntersections both =
        countSelfIntersections(joined(sphere, sphere, Vec3(1.5, 0.1, 0.05)));
    CHECK(both.pairs >= 24);
    // One vertex pushed through the far side: its fan crosses the triangles there.
    Mesh poked = sphere;
    poked.vertices[1] = -1.2 * poked.vertices[1];
    CHECK(countSelfIntersections(poked).pairs > 0);
}

TEST_CASE("self-intersections: radially jittered spheres never intersect themselves",
          "[surface][oracle]") {
    // A mesh whose every vertex lies on its own ray from the centre, with the sphere's triangles,
    // is the radial graph of a positive function over the sphere: embedded by construction.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> scale(0.6, 1.4);
    for (int round = 0; round < 5; ++round) {
        Mesh m = testing::uvSphere(8 + round, 16 + 2 * round, 1.0);
        for (Vec3& v : m.vertices) v *= scale(rng);
        const testing::SelfIntersections s = countSelfIntersections(m);
        INFO("round " << round << ": " << s.tested << " pairs tested");
        CHECK(s.pairs == 0);
        CHECK(s.tested > 0);
    }
}

TEST_CASE("self-intersections: triangles in one plane", "[surface][oracle]") {
    SECTION("a square's two halves share an edge and meet nowhere else") {
        CHECK(countSelfIntersections(square()).pairs == 0);
    }
    SECTION("a triangle folded flat onto its neighbour overlaps it") {
        Mesh m = square();
        m.triangles[1] = {0, 2, 1};  // the same corners as the first: lies on it
        CHECK(countSelfIntersections(m).pairs == 1);
        m = square();
        m.vertices[3] = Vec3(0.8, 0.1, 0.0);  // the second half swung over the first
        CHECK(countSelfIntersections(m).pairs == 1);
    }
    SECTION("a third triangle overlapping the square, sharing no corner, crosses both halves") {
        Mesh m = square();
        m.vertices.insert(m.vertices.end(),
                          {Vec3(0.5, -0.5, 0), Vec3(1.5, 0.5, 0), Vec3(0.4, 0.6, 0)});
        m.triangles.push_back({4, 5, 6});
        CHECK(countSelfIntersections(m).pairs == 2);
    }
    SECTION("a fan around a shared corner, side by side, does not overlap") {
        Mesh m;
        m.vertices.push_back(Vec3(0.0));
        for (int k = 0; k < 6; ++k)
            m.vertices.push_back(Vec3(std::cos(k * M_PI / 3), std::sin(k * M_PI / 3), 0.0));
        for (std::uint32_t k = 0; k < 6; ++k) m.triangles.push_back({0, 1 + k, 1 + (k + 1) % 6});
        CHECK(countSelfIntersections(m).pairs == 0);
        // Two of its blades swapped over each other: they now overlap near the centre.
        m.vertices[2] = Vec3(std::cos(2.5 * M_PI / 3), std::sin(2.5 * M_PI / 3), 0.0);
        CHECK(countSelfIntersections(m).pairs > 0);
    }
}

TEST_CASE("self-intersections: triangles sharing a corner that cross, and that only touch",
          "[surface][oracle]") {
    Mesh m;
    m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.3, 0.3, -0.5),
                  Vec3(0.3, 0.3, 0.5)};
    // The second triangle's far edge pierces the first (it runs from below to above its plane,
    // inside it): they cross along a segment from the shared corner.
    m.triangles = {{0, 1, 2}, {0, 3, 4}};
    CHECK(countSelfIntersections(m).pairs == 1);
    // Standing on the shared corner alone, above the plane: only the corner is common.
    m.vertices[3] = Vec3(0.3, 0.3, 0.2);
    CHECK(countSelfIntersections(m).pairs == 0);
    // A vertical triangle on the shared corner, leaning away from the first: it meets the plane
    // only along a line outside the first triangle.
    m.vertices[3] = Vec3(-0.5, -0.2, -0.5);
    m.vertices[4] = Vec3(-0.5, -0.2, 0.5);
    CHECK(countSelfIntersections(m).pairs == 0);
}

TEST_CASE("self-intersections: a neighbour tilted a hair out of the plane beside a triangle",
          "[surface][oracle]") {
    // From the contour test's spherical dimple: a triangle of the block's top face, and beside it,
    // sharing a corner, one whose other corners lie 2.4e-8 and 6.5e-8 below the face, either side
    // of the tolerance (1e-9 of the diagonal: 4.1e-8 with the far vertex that sets the box). The
    // planes cross along a line through the shared corner that runs into the first triangle, and
    // only the corner is common. Taking the nearer corner as on the plane (and the line through
    // it) made this a crossing.
    Mesh m;
    m.vertices = {Vec3(0.0),
                  Vec3(-1.0, -1.0, 0.0),
                  Vec3(-1.0, 0.0, 0.0),
                  Vec3(-0.476157, 0.079814, -2.4e-8),
                  Vec3(0.510158, 0.295019, -6.5e-8),
                  Vec3(30.0, 30.0, 20.0)};
    m.triangles = {{0, 1, 2}, {3, 0, 4}};
    CHECK(countSelfIntersections(m).pairs == 0);
    // Lowered 1e-6 more at its far corner, the neighbour's plane tilts through the first
    // triangle, and it still meets it only at the corner.
    m.vertices[4].z -= 1e-6;
    CHECK(countSelfIntersections(m).pairs == 0);
    // Its near corner moved over the first triangle: below its plane, the neighbour lies under it,
    // meeting it at the corner alone; 2.4e-8 above it, the neighbour passes through it.
    m.vertices[3] = Vec3(-0.6, -0.3, -2.4e-8);
    CHECK(countSelfIntersections(m).pairs == 0);
    m.vertices[3].z = 2.4e-8;
    CHECK(countSelfIntersections(m).pairs == 1);
}
