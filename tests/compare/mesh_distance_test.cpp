// Exact point-to-mesh distance against a brute-force oracle that shares no code with it: every
// triangle is tried, and each triangle's nearest point comes from the plane's normal equations
// (a 2 x 2 solve in the triangle's own parameters) when that lands inside, else from the three
// three edges, each by a ternary search on its convex distance function.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "dexelmill/compare/mesh_distance.h"

using namespace dexelmill;

namespace {

/// min over t in [0, 1] of |a + t (b - a) - p|, by ternary search on the convex function.
double oracleSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
    auto f = [&](double t) { return glm::length(a + t * (b - a) - p); };
    double lo = 0.0, hi = 1.0;
    for (int i = 0; i < 100; ++i) {
        const double m1 = lo + (hi - lo) / 3.0, m2 = hi - (hi - lo) / 3.0;
        if (f(m1) < f(m2)) hi = m2;
        else lo = m1;
    }
    return std::min({f(0.0), f(1.0), f(0.5 * (lo + hi))});
}

double oracleTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 u = b - a, v = c - a, w = p - a;
    const double uu = glm::dot(u, u), uv = glm::dot(u, v), vv = glm::dot(v, v);
    const double det = uu * vv - uv * uv;
    double best = std::min({oracleSegment(p, a, b), oracleSegment(p, b, c), oracleSegment(p, c, a)});
    if (det > 1e-18 * uu * vv) {
        const double wu = glm::dot(w, u), wv = glm::dot(w, v);
        const double s = (vv * wu - uv * wv) / det, t = (uu * wv - uv * wu) / det;
        if (s >= 0.0 && t >= 0.0 && s + t <= 1.0) best = std::min(best, glm::length(a + s * u + t * v - p));
    }
    return best;
}

double oracleMesh(const Mesh& m, const Vec3& p) {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& t : m.triangles)
        best = std::min(best, oracleTriangle(p, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]));
    return best;
}

/// A soup of random triangles in a 10 mm cube, some of them slivers, needles and points.
Mesh soup(std::mt19937_64& rng, int n) {
    std::uniform_real_distribution<double> u(0.0, 10.0), small(-0.3, 0.3);
    Mesh m;
    for (int i = 0; i < n; ++i) {
        const Vec3 a(u(rng), u(rng), u(rng));
        Vec3 b = a + Vec3(small(rng), small(rng), small(rng)) * 5.0;
        Vec3 c = a + Vec3(small(rng), small(rng), small(rng)) * 5.0;
        if (i % 17 == 3) c = a + 0.5 * (b - a);  // collinear
        if (i % 23 == 5) b = c = a;               // a point
        if (i % 29 == 7) b = a;                   // a segment
        const auto base = std::uint32_t(m.vertices.size());
        m.vertices.push_back(a);
        m.vertices.push_back(b);
        m.vertices.push_back(c);
        m.triangles.push_back({base, base + 1, base + 2});
    }
    return m;
}

}  // namespace

TEST_CASE("mesh distance: equals the brute-force minimum over every triangle", "[compare][distance]") {
    // Seeds 4 to 6 round the corners to floats, which the index keeps in single precision.
    for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
        std::mt19937_64 rng(seed);
        Mesh m = soup(rng, 300);
        if (seed > 3)
            for (Vec3& v : m.vertices) v = Vec3(glm::vec3(v));
        const MeshDistance index(m);
        REQUIRE(index.triangleCount() == 300);
        std::uniform_real_distribution<double> u(-5.0, 15.0);
        for (int i = 0; i < 200; ++i) {
            const Vec3 p(u(rng), u(rng), u(rng));
            const MeshDistance::Nearest n = index.nearest(p);
            const double expected = oracleMesh(m, p);
            INFO("seed " << seed << " point " << p.x << " " << p.y << " " << p.z);
            CHECK(n.distance == Approx(expected).margin(1e-9));
            // The point it names is on the triangle it names, at that distance.
            const auto& t = m.triangles[n.triangle];
            CHECK(oracleTriangle(n.point, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]) <= 1e-9);
            CHECK(glm::length(n.point - p) == Approx(n.distance).margin(1e-12));
        }
    }
}

TEST_CASE("mesh distance: points on the surface, at vertices and far away", "[compare][distance]") {
    // A unit cube's 12 triangles.
    Mesh m;
    for (int i = 0; i < 8; ++i) m.vertices.emplace_back(double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1));
    const std::uint32_t f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : f) {
        m.triangles.push_back({q[0], q[1], q[2]});
        m.triangles.push_back({q[0], q[2], q[3]});
    }
    const MeshDistance index(m);
    CHECK(index.distance(Vec3(0.5, 0.5, 0.5)) == Approx(0.5));
    CHECK(index.distance(Vec3(0.5, 0.25, 0.9)) == Approx(0.1));
    CHECK(index.distance(Vec3(0.3, 0.7, 1.0)) == 0.0);
    CHECK(index.distance(Vec3(1.0, 1.0, 1.0)) == 0.0);
    CHECK(index.distance(Vec3(2.0, 2.0, 2.0)) == Approx(std::sqrt(3.0)));
    CHECK(index.distance(Vec3(0.5, -3.0, 4.0)) == Approx(std::sqrt(18.0)));
    CHECK(index.distance(Vec3(1e6, 0.5, 0.5)) == Approx(1e6 - 1.0));
    // A point straight above an edge's midpoint, and one inside near a corner.
    CHECK(index.distance(Vec3(0.5, -1.0, -1.0)) == Approx(std::sqrt(2.0)));
    CHECK(index.distance(Vec3(0.95, 0.9, 0.98)) == Approx(0.02));
}

TEST_CASE("mesh distance: thin triangles, to rounding, for points on them and off them",
          "[compare][distance][degenerate]") {
    // Slivers as CAD tessellations make them, 1e-2 to 1e-5 as high as they are long, 1 to 21 mm
    // long, up to 100 mm from the origin, in random directions. Each is built from unit vectors
    // d and e, e across d, so its normal d x e is known whole; p lies on it at barycentric (s, t),
    // or z along that normal from there. The distance is then |z| up to the rounding of p's own
    // sum (some 1e-14 mm): the barycentric weights of dot products lost up to 0.55 um here.
    std::mt19937_64 rng(20261204);
    std::uniform_real_distribution<double> u(-1.0, 1.0), w(0.0, 1.0);
    double worst = 0.0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 a(100.0 * u(rng), 100.0 * u(rng), 100.0 * u(rng));
        const Vec3 d = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
        const Vec3 e = glm::normalize(glm::cross(d, Vec3(u(rng), u(rng), u(rng))));
        const double length = 1.0 + 20.0 * w(rng), height = length * std::pow(10.0, -2.0 - 3.0 * w(rng));
        const Vec3 b = a + length * d, c = a + length * w(rng) * d + height * e;
        double s = w(rng), t = w(rng);
        if (s + t > 1.0) s = 1.0 - s, t = 1.0 - t;
        const double z = i % 2 == 0 ? 0.0 : 0.01 * u(rng);
        const Vec3 p = a + s * (b - a) + t * (c - a) + z * glm::cross(d, e);
        const double error = std::abs(glm::length(closestPointOnTriangle(p, a, b, c) - p) - std::abs(z));
        worst = std::max(worst, error);
    }
    INFO("the largest error, mm: " << worst);
    CHECK(worst <= 1e-8);
}

TEST_CASE("mesh distance: empty and one-triangle meshes", "[compare][distance][degenerate]") {
    const MeshDistance none{Mesh{}};
    CHECK(std::isinf(none.distance(Vec3(0.0))));
    Mesh one;
    one.vertices = {Vec3(0.0), Vec3(2.0, 0.0, 0.0), Vec3(0.0, 2.0, 0.0)};
    one.triangles = {{0, 1, 2}};
    const MeshDistance index(one);
    CHECK(index.distance(Vec3(0.5, 0.5, 3.0)) == Approx(3.0));
    CHECK(index.distance(Vec3(-1.0, -1.0, 0.0)) == Approx(std::sqrt(2.0)));
    CHECK(index.distance(Vec3(2.0, 2.0, 0.0)) == Approx(std::sqrt(2.0)));
    // Every triangle a point: the distance to the nearest of them.
    Mesh points;
    points.vertices = {Vec3(1.0, 1.0, 1.0), Vec3(4.0, 1.0, 1.0)};
    points.triangles = {{0, 0, 0}, {1, 1, 1}};
    CHECK(MeshDistance(points).distance(Vec3(3.0, 1.0, 1.0)) == Approx(1.0));
}

namespace {

/// An L-shaped prism, closed and facing out: the polygon (0,0) (10,0) (10,4) (4,4) (4,10) (0,10),
/// counter-clockwise seen from +z, from z = 0 to 5. The caps are fans from the reflex corner (4,4),
/// which sees every other corner.
Mesh lPrism() {
    const double xy[6][2] = {{0, 0}, {10, 0}, {10, 4}, {4, 4}, {4, 10}, {0, 10}};
    Mesh m;
    for (double z : {0.0, 5.0})
        for (const auto& c : xy) m.vertices.emplace_back(c[0], c[1], z);
    for (std::uint32_t i : {4u, 5u, 0u, 1u}) {
        const std::uint32_t j = (i + 1) % 6;
        m.triangles.push_back({3, j, i});          // bottom, facing -z
        m.triangles.push_back({9, 6 + i, 6 + j});  // top, facing +z
    }
    for (std::uint32_t i = 0; i < 6; ++i) {
        const std::uint32_t j = (i + 1) % 6;
        m.triangles.push_back({i, j, 6 + j});
        m.triangles.push_back({i, 6 + j, 6 + i});
    }
    return m;
}

/// Whether p is inside the L prism, from its definition.
bool insideL(const Vec3& p) {
    const bool inPlan = (p.x > 0 && p.x < 10 && p.y > 0 && p.y < 4) || (p.x > 0 && p.x < 4 && p.y > 0 && p.y < 10);
    return inPlan && p.z > 0 && p.z < 5;
}

/// Whether p lies on the L prism's surface (on a face's plane within its extent).
bool onL(const Vec3& p) {
    const bool inPlan = (p.x >= 0 && p.x <= 10 && p.y >= 0 && p.y <= 4) || (p.x >= 0 && p.x <= 4 && p.y >= 0 && p.y <= 10);
    return inPlan && p.z >= 0 && p.z <= 5 && !insideL(p);
}

}  // namespace

TEST_CASE("mesh distance: the sign, inside a non-convex solid, for any orientation", "[compare][distance]") {
    const Mesh outward = lPrism();
    Mesh inward = outward;
    for (auto& t : inward.triangles) std::swap(t[1], t[2]);
    Mesh mixed = outward;  // one face turned: no consistent orientation, so rays decide every sign
    std::swap(mixed.triangles[5][1], mixed.triangles[5][2]);
    Mesh open = outward;
    open.triangles.pop_back();
    CHECK(MeshDistance(outward).orientation() == 1);
    CHECK(MeshDistance(inward).orientation() == -1);
    CHECK(MeshDistance(mixed).orientation() == 0);
    CHECK(MeshDistance(open).orientation() == 0);

    // Random points, and points on a 0.5 mm lattice: many of those lie on faces, on edges, at
    // corners and in line with them, where a ray meets an edge.
    std::vector<Vec3> points;
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-2.0, 12.0);
    for (int i = 0; i < 400; ++i) points.emplace_back(u(rng), u(rng), 0.5 * u(rng));
    for (int i = -2; i <= 24; i += 1)
        for (int j = -2; j <= 24; j += 3)
            for (int k = -2; k <= 12; k += 2) points.emplace_back(0.5 * i, 0.5 * j, 0.5 * k);
    // The outward L once more without its orientation checked: rays decide every sign.
    CHECK(MeshDistance(outward, false).orientation() == 0);
    for (const auto& [m, orient] : std::vector<std::pair<const Mesh*, bool>>{
             {&outward, true}, {&inward, true}, {&mixed, true}, {&outward, false}}) {
        const MeshDistance index(*m, orient);
        std::uint32_t hint = 0;
        for (const Vec3& p : points) {
            INFO("orientation " << index.orientation() << ", point " << p.x << " " << p.y << " " << p.z);
            const double d = oracleMesh(outward, p);
            const double s = index.signedDistance(p, &hint);
            if (onL(p)) {  // zero, to the rounding of a point on a triangle
                CHECK(d <= 1e-12);
                CHECK(std::abs(s) <= 1e-12);
                continue;
            }
            CHECK(index.inside(p) == insideL(p));
            CHECK(std::abs(s) == Approx(d).margin(1e-12));
            CHECK((s < 0.0) == insideL(p));
            CHECK(index.nearest(p, &hint).distance == Approx(d).margin(1e-12));
        }
    }
}

TEST_CASE("mesh distance: shells facing different ways, and a cavity", "[compare][distance]") {
    // A 10 mm cube with a 4 mm cavity in its middle (the cavity's faces point into it), and a
    // separate 2 mm cube beside it.
    auto cube = [](Mesh& m, const Vec3& lo, double side, bool out) {
        const auto base = std::uint32_t(m.vertices.size());
        for (int i = 0; i < 8; ++i) m.vertices.push_back(lo + side * Vec3(i & 1, (i >> 1) & 1, (i >> 2) & 1));
        const std::uint32_t f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
        for (const auto& q : f) {
            m.triangles.push_back({base + q[0], base + (out ? q[1] : q[2]), base + (out ? q[2] : q[1])});
            m.triangles.push_back({base + q[0], base + (out ? q[2] : q[3]), base + (out ? q[3] : q[2])});
        }
    };
    Mesh good;
    cube(good, Vec3(0.0), 10.0, true);
    cube(good, Vec3(3.0), 4.0, false);
    cube(good, Vec3(20.0, 0.0, 0.0), 2.0, true);
    Mesh flipped;  // the small cube inside out: every edge still pairs, and the volume is positive
    cube(flipped, Vec3(0.0), 10.0, true);
    cube(flipped, Vec3(3.0), 4.0, false);
    cube(flipped, Vec3(20.0, 0.0, 0.0), 2.0, false);
    CHECK(MeshDistance(good).orientation() == 1);
    CHECK(MeshDistance(flipped).orientation() == 0);
    // Two cubes sharing an edge, its vertices shared: every edge runs both ways, but four
    // triangles meet at that one, so the mesh is not a 2-manifold.
    Mesh touching;
    cube(touching, Vec3(0.0), 10.0, true);
    cube(touching, Vec3(10.0, 10.0, 0.0), 10.0, true);
    for (auto& t : touching.triangles)
        for (auto& v : t)
            for (std::uint32_t w = 0; w < v; ++w)
                if (touching.vertices[w] == touching.vertices[v]) {
                    v = w;
                    break;
                }
    CHECK(MeshDistance(touching).orientation() == 0);
    Mesh collapsed = good;  // a triangle with a repeated corner
    collapsed.triangles.push_back({0, 0, 1});
    CHECK(MeshDistance(collapsed).orientation() == 0);
    // Inside the solid: between the outer faces and the cavity, and in the small cube; outside:
    // in the cavity, between the cubes, beyond them.
    const std::vector<std::pair<Vec3, double>> cases{
        {Vec3(1.0, 5.0, 5.0), -1.0},  {Vec3(5.0, 5.0, 5.0), 2.0},  {Vec3(5.0, 5.0, 2.5), -0.5},
        {Vec3(21.0, 1.0, 1.5), -0.5}, {Vec3(15.0, 1.0, 1.0), 5.0}, {Vec3(-3.0, 5.0, 5.0), 3.0}};
    for (const Mesh* m : std::vector<const Mesh*>{&good, &flipped}) {
        const MeshDistance index(*m);
        for (const auto& [p, expected] : cases) {
            INFO("orientation " << index.orientation() << ", point " << p.x << " " << p.y << " " << p.z);
            CHECK(index.signedDistance(p) == Approx(expected).margin(1e-12));
        }
    }
}
