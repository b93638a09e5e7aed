// The mesh's crossing test (surface/detail/crossings.h) against the tests' own
// self-intersection count (support/self_intersection.h), which shares no code with it.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "surface/detail/crossings.h"
#include "support/self_intersection.h"
#include "support/uv_sphere.h"

using namespace dexelmill;

namespace {

constexpr double kTol = 1e-9;

/// Two triangles as a mesh: corners 0-2 and 3-5, with `shared` of b's first corners replaced by
/// a's (b's corner k by a's corner k).
Mesh pair(const std::array<Vec3, 6>& p, int shared) {
    Mesh m;
    m.vertices.assign(p.begin(), p.end());
    m.triangles = {{0, 1, 2}, {3, 4, 5}};
    for (int k = 0; k < shared; ++k) m.triangles[1][std::size_t(k)] = std::uint32_t(k);
    return m;
}

bool libraryCross(const Mesh& m) {
    const auto at = [&](const Mesh::Triangle& t) {
        return std::array<Vec3, 3>{m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]};
    };
    return detail::trianglesCross(m.triangles[0], at(m.triangles[0]), m.triangles[1],
                                  at(m.triangles[1]), kTol);
}

}  // namespace

TEST_CASE("crossings: pairs of triangles agree with the brute-force count", "[surface][oracle]") {
    // Random pairs in a unit cube, sharing no corner, one or two, and pairs in one plane (z = 0.5
    // with a tilt of 0 or a hair): every answer must be the oracle's.
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> x(0.0, 1.0);
    int crossing = 0, total = 0;
    for (int shared = 0; shared <= 2; ++shared)
        for (int flat = 0; flat <= 1; ++flat)
            for (int i = 0; i < 3000; ++i) {
                std::array<Vec3, 6> p;
                for (Vec3& v : p) v = Vec3(x(rng), x(rng), flat ? 0.5 : x(rng));
                const Mesh m = pair(p, shared);
                const bool oracle = testing::countSelfIntersections(m).pairs == 1;
                INFO("shared " << shared << ", flat " << flat << ", pair " << i);
                CHECK(libraryCross(m) == oracle);
                crossing += oracle;
                ++total;
            }
    // Both answers occur in every kind of pair but a shared edge out of the plane.
    INFO(crossing << " of " << total << " cross");
    CHECK(crossing > total / 20);
    CHECK(crossing < total / 2);
}

TEST_CASE("crossings: the pieces that pass through the mesh are found, each once",
          "[surface][oracle]") {
    // Two triangles far apart and a third through the first: the list holds the crossing pair
    // alone, whichever of them is a piece.
    Mesh m;
    m.vertices = {Vec3(0, 0, 0),      Vec3(1, 0, 0),     Vec3(0, 1, 0),       // 0: in z = 0
                  Vec3(5, 5, 5),      Vec3(6, 5, 5),     Vec3(5, 6, 5),       // 1: far away
                  Vec3(0.2, 0.2, -1), Vec3(0.3, 0.2, 1), Vec3(0.2, 0.3, 1)};  // 2: through 0
    m.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
    const std::vector<std::uint32_t> all{0, 1, 2};
    CHECK(detail::crossingTriangles(m, {2}, all, kTol) == std::vector<std::uint32_t>{0, 2});
    CHECK(detail::crossingTriangles(m, {0}, all, kTol) == std::vector<std::uint32_t>{0, 2});
    CHECK(detail::crossingTriangles(m, {0, 1, 2}, all, kTol) == std::vector<std::uint32_t>{0, 2});
    CHECK(detail::crossingTriangles(m, {1}, all, kTol).empty());
    // Moved clear of the first, nothing crosses.
    for (std::uint32_t v : {6u, 7u, 8u}) m.vertices[v].x += 2.0;
    CHECK(detail::crossingTriangles(m, {0, 1, 2}, all, kTol).empty());
}

TEST_CASE("crossings: on a jittered sphere, the list is the brute-force count's",
          "[surface][oracle]") {
    // A UV sphere whose vertices are pushed in and out along their rays stays embedded; pushing
    // some through the centre and out past the far side makes crossings. The library must list
    // every triangle of the pairs the oracle lists, and nothing else when the oracle lists all.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> scale(0.7, 1.3);
    for (int round = 0; round < 4; ++round) {
        Mesh m = testing::uvSphere(10, 20, 1.0);
        for (Vec3& v : m.vertices) v *= scale(rng);
        for (int k = 0; k < round; ++k) m.vertices[std::size_t(7 + 23 * k)] *= -1.6;
        std::vector<std::uint32_t> all(m.triangles.size());
        for (std::uint32_t t = 0; t < all.size(); ++t) all[t] = t;
        const std::vector<std::uint32_t> listed = detail::crossingTriangles(m, all, all, kTol);
        const testing::SelfIntersections oracle = testing::countSelfIntersections(m);
        INFO("round " << round << ": " << listed.size() << " listed, " << oracle.pairs
                      << " pairs counted");
        CHECK(listed.empty() == (oracle.pairs == 0));
        CHECK(listed.empty() == (round == 0));
        // Every pair the oracle lists (up to its cap) is listed by the library, and when the cap
        // holds them all, nothing else is.
        std::vector<std::uint32_t> counted;
        for (const auto& pr : oracle.some) counted.insert(counted.end(), pr.begin(), pr.end());
        std::sort(counted.begin(), counted.end());
        counted.erase(std::unique(counted.begin(), counted.end()), counted.end());
        for (std::uint32_t t : counted) CHECK(std::binary_search(listed.begin(), listed.end(), t));
        if (oracle.pairs < testing::SelfIntersections::kMaxListed) CHECK(listed == counted);
    }
}
