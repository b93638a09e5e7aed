// The points the deviation is measured at (compare/detail/surface_samples.h): every point of a
// triangle within spacing / sqrt(3) of one, checked by brute force at random points of fat
// triangles and slivers; the shares of the area; the points a sliver costs; and the spacing the
// bisection finds, against counts worked out by hand.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "compare/detail/surface_samples.h"

using namespace dexelmill;

namespace {

Mesh triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
    Mesh m;
    m.vertices = {a, b, c};
    m.triangles = {{0, 1, 2}};
    return m;
}

/// A budget no test triangle reaches: the spacing is then the finest asked for.
constexpr std::uint64_t kNoLimit = std::uint64_t(1) << 40;

/// The rounding of the points' coordinates (mm): a few units in the last place of 100 mm.
constexpr double kCoordinateRounding = 1e-12;

}  // namespace

TEST_CASE("surface samples: every point of a triangle lies within spacing / sqrt(3) of a measured one",
          "[compare][samples]") {
    const double s = 1.0;
    // Fat and thin, acute, right and obtuse: a sliver's apex over the middle of its longest edge,
    // over one end (a right angle) and past it (an obtuse angle); a triangle as high as a third of
    // its base (near where rows and the lattice cost the same); an equilateral one.
    const std::vector<Mesh> triangles{
        triangle(Vec3(0, 0, 0), Vec3(100, 0, 0), Vec3(50, 0.01, 0)),
        triangle(Vec3(0, 0, 0), Vec3(100, 0, 0), Vec3(0, 0.3, 0.2)),
        triangle(Vec3(0, 0, 0), Vec3(40, 0, 0), Vec3(-3, 1.5, 0)),
        triangle(Vec3(1, 2, 3), Vec3(31, 2, 3), Vec3(12, 2, 13)),
        triangle(Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(5, 5 * std::sqrt(3.0), 0)),
        triangle(Vec3(0, 0, 0), Vec3(7, 0, 0), Vec3(0, 0, 7)),
        triangle(Vec3(0, 0, 0), Vec3(0.5, 0, 0), Vec3(0.2, 0.3, 0)),  // measured at its corners
    };
    std::mt19937 random(20240611);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (std::size_t k = 0; k < triangles.size(); ++k) {
        INFO("triangle " << k);
        const Mesh& m = triangles[k];
        const SurfaceSamples samples = sampleSurface(m, s, kNoLimit);
        REQUIRE(samples.spacing == s);
        std::vector<Vec3> measured(m.vertices.begin(), m.vertices.end());
        measured.insert(measured.end(), samples.points.begin(), samples.points.end());
        const Vec3 &a = m.vertices[0], &b = m.vertices[1], &c = m.vertices[2];
        double farthest = 0.0;
        for (int i = 0; i < 20000; ++i) {
            double u = unit(random), w = unit(random);
            if (u + w > 1.0) u = 1.0 - u, w = 1.0 - w;
            // A tenth of the points on the edges, where the patterns' rows and copies end.
            if (i % 10 == 0) w = 0.0;
            if (i % 10 == 1) w = 1.0 - u;
            const Vec3 x = a + u * (b - a) + w * (c - a);
            double nearest = std::numeric_limits<double>::infinity();
            for (const Vec3& p : measured) nearest = std::min(nearest, glm::length(x - p));
            farthest = std::max(farthest, nearest);
        }
        CHECK(farthest <= s / std::sqrt(3.0) + kCoordinateRounding);

        // The shares add up to the triangle's area, none negative, and each lies within the
        // spacing of its point: the shares' mean of a function that changes by at most 1 per mm
        // lies within the spacing of its mean over the triangle (at the centroid: it is linear).
        const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
        double sum = 0.0, mean = 0.0;
        const Vec3 direction = glm::normalize(Vec3(0.3, -0.5, 0.8));
        for (std::size_t v = 0; v < 3; ++v) {
            CHECK(samples.vertexArea[v] >= 0.0);
            sum += samples.vertexArea[v];
            mean += samples.vertexArea[v] * glm::dot(m.vertices[v], direction);
        }
        for (std::size_t p = 0; p < samples.points.size(); ++p) {
            CHECK(samples.pointArea[p] >= 0.0);
            sum += samples.pointArea[p];
            mean += samples.pointArea[p] * glm::dot(samples.points[p], direction);
        }
        CHECK(sum == Approx(area).epsilon(1e-12));
        CHECK(std::abs(mean / area - glm::dot((a + b + c) / 3.0, direction)) <= s);
    }
}

TEST_CASE("surface samples: a sliver is sampled along its length, not cut into k^2 copies", "[compare][samples]") {
    // 100 mm long, 0.01 mm high, at s = 1: r = 1 / sqrt(3) = 0.57735; one row (0.01 <= r /
    // sqrt(2)), its points at most t = 2 sqrt(r^2 - 0.01^2) = 1.15453 apart: ceil(100 / 1.15453)
    // = 87 pieces, 88 points of which A and B are corners: 86 added. Copies would number
    // 100^2 and add 101 x 102 / 2 - 3 = 5148 points.
    const TrianglePattern sliver = trianglePattern({100.0, 0.01}, 1.0);
    CHECK(sliver.rows == 1);
    CHECK(sliver.added == 86);
    // Equilateral, 10 mm sides: the lattice, 10 pieces along each edge, 11 x 12 / 2 - 3 = 63
    // added.
    const TrianglePattern fat = trianglePattern({10.0, 5.0 * std::sqrt(3.0)}, 1.0);
    CHECK(fat.rows == 0);
    CHECK(fat.pieces == 10);
    CHECK(fat.added == 63);
    // A triangle no longer than the spacing is measured at its corners.
    CHECK(trianglePattern({0.9, 0.5}, 1.0).added == 0);
    // Rows: 1.5 mm high at s = 1 needs ceil(sqrt(2) 1.5 / r) = 4 rows, 0.375 mm apart, their points
    // t = 2 sqrt(r^2 - 0.375^2) = 0.87797 apart; rows of 40, 30, 20 and 10 mm take 46, 35, 23 and 12
    // pieces: 47 + 36 + 24 + 13 - 2 = 118 added, against the lattice's 41 x 42 / 2 - 3 = 858.
    const TrianglePattern thin = trianglePattern({40.0, 1.5}, 1.0);
    CHECK(thin.rows == 4);
    CHECK(thin.added == 118);
}

TEST_CASE("surface samples: the spacing is the finest the budget allows, to within 2 %", "[compare][samples]") {
    // A right triangle with 10 mm legs: its hypotenuse L = 14.1421 mm. Cut k times along each edge
    // (k = ceil(L / s)) it adds (k + 1) (k + 2) / 2 - 3 points: 65,338 at k = 360, 65,700 at 361. A
    // budget of 2^16 so allows s >= L / 360 and no finer; rows would add more (about 1.5 L^2 / 2
    // s^2 here, the height being L / 2).
    const Mesh m = triangle(Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(0, 10, 0));
    const double L = 10.0 * std::sqrt(2.0);
    const SurfaceSamples samples = sampleSurface(m, 1e-3, std::uint64_t(1) << 16);
    CHECK(samples.spacing >= L / 360.0 * (1.0 - 1e-12));
    CHECK(samples.spacing < 1.02 * L / 360.0);
    const double k = std::ceil(L / samples.spacing);
    CHECK(samples.points.size() == std::size_t((k + 1) * (k + 2) / 2 - 3));
    CHECK(samples.points.size() <= std::size_t(1) << 16);
    // The finest asked for is kept when it meets the budget; a budget of 0 leaves the corners.
    CHECK(sampleSurface(m, 0.5, std::uint64_t(1) << 16).spacing == 0.5);
    const SurfaceSamples none = sampleSurface(m, 1e-3, 0);
    CHECK(none.points.empty());
    CHECK(none.spacing >= L);
    CHECK(none.vertexArea[0] + none.vertexArea[1] + none.vertexArea[2] == Approx(50.0));
}
