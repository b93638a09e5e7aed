// checkMesh against a brute-force oracle that shares no code with it: every edge counted in an
// ordered map, every vertex normal (by area and by angle) summed triangle by triangle, on closed meshes damaged at random
// in every way the check names (fixed seeds).
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include <tbb/task_arena.h>

#include "dexelmill/surface/mesh.h"
#include "support/uv_sphere.h"

using namespace dexelmill;

namespace {

/// Triangles within 1e-5 (cosine) of facing across their vertices' normals, by the oracle.
std::size_t& nearlyFoldedCount() {
    static std::size_t n = 0;
    return n;
}
std::size_t nearlyFolded(const MeshCheck&) { return nearlyFoldedCount(); }

/// Triangles facing against their vertices' area-weighted normals, by the oracle: checkMesh lists
/// them (with the degenerate ones) as the triangles to repair, folded or not.
std::size_t& areaFacingCount() {
    static std::size_t n = 0;
    return n;
}

/// The oracle's count of what checkMesh reports.
MeshCheck bruteForce(const Mesh& m) {
    MeshCheck r;
    r.vertexCount = m.vertices.size();
    r.triangleCount = m.triangles.size();
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<int, int>> edges;  // (lo, hi) -> (lo->hi, hi->lo)
    std::vector<bool> used(m.vertices.size(), false);
    std::vector<Vec3> normal(m.vertices.size(), Vec3(0.0)), byAngle(m.vertices.size(), Vec3(0.0));
    for (const Mesh::Triangle& t : m.triangles) {
        const Vec3 a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
        const Vec3 n = glm::cross(b - a, c - a);
        const std::array<Vec3, 3> p{a, b, c};
        for (int k = 0; k < 3; ++k) {
            used[t[k]] = true;
            normal[t[k]] += n;
            // Each triangle's unit normal, weighted by its angle at the vertex.
            const Vec3 u = p[std::size_t((k + 1) % 3)] - p[std::size_t(k)], w = p[std::size_t((k + 2) % 3)] - p[std::size_t(k)];
            const double lu = glm::length(u), lw = glm::length(w), ln = glm::length(n);
            if (lu > 0.0 && lw > 0.0 && ln > 0.0)
                byAngle[t[k]] += n / ln * std::acos(std::clamp(glm::dot(u, w) / (lu * lw), -1.0, 1.0));
            const std::uint32_t p = t[k], q = t[(k + 1) % 3];
            if (p == q) continue;
            auto& e = edges[{std::min(p, q), std::max(p, q)}];
            (p < q ? e.first : e.second)++;
        }
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
            ++r.degenerateTriangles;
            continue;
        }
        const double l2 = std::max({glm::dot(b - a, b - a), glm::dot(c - b, c - b), glm::dot(a - c, a - c)});
        if (!(glm::length(n) > 1e-12 * l2)) ++r.degenerateTriangles;
        r.area += 0.5 * glm::length(n);
        r.signedVolume += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    for (const auto& [key, uses] : edges) {
        ++r.edgeCount;
        const int n = uses.first + uses.second;
        if (n == 1) ++r.boundaryEdges;
        else if (n > 2) ++r.nonManifoldEdges;
        else if (uses.first != 1) ++r.misorientedEdges;
    }
    r.unusedVertices = std::size_t(std::count(used.begin(), used.end(), false));
    for (std::vector<Vec3>* list : {&normal, &byAngle})
        for (Vec3& n : *list)
            if (glm::length(n) > 0.0) n = glm::normalize(n);
    nearlyFoldedCount() = 0;
    areaFacingCount() = 0;
    for (const Mesh::Triangle& t : m.triangles) {
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
        const Vec3 a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
        const Vec3 area = glm::cross(b - a, c - a);
        const double l2 = std::max({glm::dot(b - a, b - a), glm::dot(c - b, c - b), glm::dot(a - c, a - c)});
        if (!(glm::length(area) > 1e-12 * l2)) continue;  // degenerate: no facing to speak of
        // Folded when it faces against both sums; the larger cosine decides.
        double facing = -2.0;
        for (const std::vector<Vec3>* list : {&normal, &byAngle}) {
            const Vec3 sum = (*list)[t[0]] + (*list)[t[1]] + (*list)[t[2]];
            const double scale = glm::length(area) * glm::length(sum);
            const double cosine = scale > 0.0 ? glm::dot(area, sum) / scale : 0.0;
            if (list == &normal && cosine < 1e-5) ++areaFacingCount();
            facing = std::max(facing, cosine);
        }
        if (facing < -1e-5) ++r.foldedTriangles;
        else if (facing < 1e-5) ++nearlyFoldedCount();
    }
    return r;
}

void compare(const MeshCheck& got, const MeshCheck& want) {
    CHECK(got.edgeCount == want.edgeCount);
    CHECK(got.boundaryEdges == want.boundaryEdges);
    CHECK(got.nonManifoldEdges == want.nonManifoldEdges);
    CHECK(got.misorientedEdges == want.misorientedEdges);
    CHECK(got.degenerateTriangles == want.degenerateTriangles);
    // checkMesh keeps unit vertex normals in float (7 digits): a triangle within 1e-5 of facing
    // exactly across its normals may count either way.
    CHECK(got.foldedTriangles >= want.foldedTriangles);
    CHECK(got.foldedTriangles <= want.foldedTriangles + nearlyFolded(want));
    CHECK(got.unusedVertices == want.unusedVertices);
    CHECK(got.area == Approx(want.area).epsilon(1e-12));
    // The enclosed volume is defined for closed meshes only (otherwise it depends on the origin).
    if (want.closedManifold()) CHECK(got.signedVolume == Approx(want.signedVolume).epsilon(1e-9).margin(1e-9));
}

}  // namespace

TEST_CASE("checkMesh: a closed sphere is ok", "[surface][mesh]") {
    const Mesh m = testing::uvSphere(12, 24, 5.0);
    const MeshCheck c = checkMesh(m);
    CHECK(c.ok());
    compare(c, bruteForce(m));
    CHECK(c.signedVolume > 0.0);
}

TEST_CASE("checkMesh: every kind of damage counted as a brute-force oracle counts it", "[surface][mesh]") {
    std::mt19937_64 rng(42);
    for (int trial = 0; trial < 200; ++trial) {
        Mesh m = testing::uvSphere(6 + int(rng() % 6), 8 + int(rng() % 10), 3.0);
        const int damages = 1 + int(rng() % 4);
        for (int d = 0; d < damages; ++d) {
            const std::size_t t = rng() % m.triangles.size();
            switch (rng() % 7) {
                case 0: m.triangles.erase(m.triangles.begin() + std::ptrdiff_t(t)); break;  // a hole
                case 1: std::swap(m.triangles[t][0], m.triangles[t][1]); break;            // misoriented
                case 2: m.triangles.push_back(m.triangles[t]); break;                       // non-manifold
                case 3: m.triangles[t][2] = m.triangles[t][1]; break;                       // repeated index
                case 4: {  // a sliver: the third vertex on the first edge
                    const std::uint32_t v = std::uint32_t(m.vertices.size());
                    m.vertices.push_back(0.5 * (m.vertices[m.triangles[t][0]] + m.vertices[m.triangles[t][1]]));
                    m.triangles.push_back({m.triangles[t][0], m.triangles[t][1], v});
                    break;
                }
                case 5: m.vertices[m.triangles[t][0]] *= -0.2; break;  // a vertex pushed through: folds
                default: m.vertices.push_back(Vec3(9.0)); break;      // unused
            }
        }
        INFO("trial " << trial);
        const MeshCheck want = bruteForce(m);
        // The stars are split by vertex range among the threads: any count of them, even or
        // not, gives the same check, to the last bit of the sums.
        std::vector<MeshCheck> got;
        for (int threads : {1, 2, 3, 5}) {
            tbb::task_arena arena(threads);
            got.push_back(arena.execute([&] { return checkMesh(m); }));
            INFO(threads << " threads");
            compare(got.back(), want);
            CHECK(got.back().signedVolume == got.front().signedVolume);
            CHECK(got.back().area == got.front().area);
        }
    }
}

TEST_CASE("checkMesh: a small face on a sharp vertex of a convex solid is not folded", "[surface][mesh]") {
    // A flat tetrahedron: the base ABC (normal -z, area 0.5), two faces ABD and CAD rising 0.02 to
    // D (nearly +z, area 0.225 each), and the small face BCD (area 0.052) facing (0.19, 0.19,
    // 0.96), where D lies 0.05 inside the base's edge BC in x and y. Its vertices B and C lie on
    // ridges sharper than a right angle. A convex solid turns one way everywhere, so none of its
    // faces folds. Vertex normals weighted by area (the base's, ten times BCD's, nearly cancelling
    // ABD's and CAD's) point down at B and C, and BCD faces against their sum with D's (as the
    // corner triangle of a sheet thinner than the spacing did on boat-xyzac.ngc); weighted by
    // angle they do not, and a fold needs both.
    Mesh m;
    m.vertices = {Vec3(0.0, 0.0, 0.0), Vec3(1.0, 0.0, 0.0), Vec3(0.0, 1.0, 0.0), Vec3(0.45, 0.45, 0.02)};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
    const MeshCheck c = checkMesh(m);
    REQUIRE(c.closedManifold());
    REQUIRE(c.signedVolume > 0.0);
    CHECK(c.foldedTriangles == 0);
    compare(c, bruteForce(m));
    // The repair's own test, by area alone, still takes those faces (the oracle counts them).
    CHECK(c.facingAgainstTriangles == areaFacingCount());
    CHECK(c.facingAgainstTriangles > 0);
}

TEST_CASE("checkMesh: an index past the vertex list", "[surface][mesh]") {
    Mesh m = testing::uvSphere(6, 8, 1.0);
    m.triangles[3][1] = 999;
    const MeshCheck c = checkMesh(m);
    CHECK(c.invalidIndices == 1);
    CHECK_FALSE(c.ok());
}

TEST_CASE("checkMesh lists the folded triangles it counts", "[surface][mesh]") {
    Mesh m = testing::uvSphere(10, 16, 4.0);
    std::vector<std::uint32_t> folded{7};
    CHECK(checkMesh(m, &folded).foldedTriangles == 0);
    CHECK(folded.empty());
    for (std::uint32_t v : {20u, 77u}) m.vertices[v] = m.vertices[v + 1] + 1.5 * (m.vertices[v + 1] - m.vertices[v]);
    const MeshCheck c = checkMesh(m, &folded);
    REQUIRE(c.foldedTriangles > 0);
    CHECK(folded.size() == c.foldedTriangles + c.degenerateTriangles);
    CHECK(std::is_sorted(folded.begin(), folded.end()));
    compare(c, bruteForce(m));
}

TEST_CASE("FoldWatch follows the folds checkMesh finds while vertices move", "[surface][mesh]") {
    std::mt19937_64 rng(7);
    for (int trial = 0; trial < 20; ++trial) {
        Mesh m = testing::uvSphere(8 + int(rng() % 6), 10 + int(rng() % 10), 3.0);
        const std::vector<Vec3, NoZeroAllocator<Vec3>> start = m.vertices;
        const int threads = 1 + int(rng() % 3);
        tbb::task_arena arena(threads);
        arena.execute([&] {
            FoldWatch watch(m);
            CHECK(watch.folded().empty());
            for (int batch = 0; batch < 15; ++batch) {
                std::vector<std::uint32_t> moved;
                const int count = int(rng() % 6);  // sometimes none
                for (int k = 0; k < count; ++k) {
                    const std::uint32_t v = std::uint32_t(rng() % m.vertices.size());
                    switch (rng() % 4) {
                        case 0: m.vertices[v] *= -0.2; break;                  // pushed through: folds
                        case 1: m.vertices[v] = start[v]; break;               // back where it was
                        case 2: m.vertices[v] = m.vertices[(v + 1) % m.vertices.size()]; break;  // onto another
                        default: m.vertices[v] *= 1.0 + 0.3 * double(rng() % 100) / 100.0; break;
                    }
                    moved.push_back(v);
                    if (rng() % 3 == 0) moved.push_back(v);  // told twice
                }
                watch.moved(moved);
                INFO("trial " << trial << ", batch " << batch << ", " << threads << " threads");
                std::vector<std::uint32_t> want;
                const MeshCheck c = checkMesh(m, &want);
                CHECK(watch.folded() == want);
                // And against the oracle, which shares no code: folded and degenerate triangles,
                // give or take those within its float margin of facing across.
                // The list holds every folded triangle, and those only the area-weighted normals
                // face against.
                const MeshCheck brute = bruteForce(m);
                CHECK(watch.folded().size() >= brute.foldedTriangles + brute.degenerateTriangles);
                CHECK(watch.folded().size() <= areaFacingCount() + brute.degenerateTriangles);
                CHECK(c.foldedTriangles + c.degenerateTriangles <= want.size());
                CHECK(c.facingAgainstTriangles + c.degenerateTriangles == want.size());
            }
        });
    }
}

TEST_CASE("repairAndCheckMesh: pulls fold vertices until none folds", "[surface][mesh]") {
    Mesh m = testing::uvSphere(10, 16, 4.0);
    const auto original = m.vertices;
    // Move three vertices across a neighbour, past it along the surface: the triangles between
    // turn over.
    for (std::uint32_t v : {20u, 45u, 77u}) m.vertices[v] = m.vertices[v + 1] + 1.5 * (m.vertices[v + 1] - m.vertices[v]);
    REQUIRE(checkMesh(m).foldedTriangles > 0);
    FoldRepair repair;
    repair.minCosine = 1e-3;
    repair.rounds = 8;
    std::size_t calls = 0;
    repair.pull = [&](std::uint32_t v, int, Vec3& x, const std::vector<std::uint32_t>& neighbours) {
        ++calls;
        CHECK(neighbours.size() >= 3);
        if (x == original[v]) return false;
        x = original[v];
        return true;
    };
    std::size_t moved = 0;
    const MeshCheck c = repairAndCheckMesh(m, repair, &moved);
    CHECK(moved == 3);
    CHECK(calls > 0);
    CHECK(c.ok());
    compare(c, bruteForce(m));
}

TEST_CASE("repairAndCheckMesh: a fold no pull can mend stays listed while others are mended", "[surface][mesh]") {
    // Two folds far apart; the pull only knows how to mend the first. The second must still be
    // listed as unrepaired (it used to be dropped once the first one's vertices moved).
    Mesh m = testing::uvSphere(10, 16, 4.0);
    const auto original = m.vertices;
    const std::uint32_t mendable = 20, stuck = 77;
    for (std::uint32_t v : {mendable, stuck})
        m.vertices[v] = m.vertices[v + 1] + 1.5 * (m.vertices[v + 1] - m.vertices[v]);
    REQUIRE(checkMesh(m).foldedTriangles > 0);
    FoldRepair repair;
    repair.pull = [&](std::uint32_t v, int, Vec3& x, const std::vector<std::uint32_t>&) {
        if (v != mendable || x == original[v]) return false;
        x = original[v];
        return true;
    };
    std::vector<std::uint32_t> unrepaired;
    const MeshCheck c = repairAndCheckMesh(m, repair, nullptr, &unrepaired);
    CHECK(m.vertices[mendable] == original[mendable]);
    const MeshCheck brute = bruteForce(m);
    compare(c, brute);
    REQUIRE(brute.foldedTriangles > 0);
    CHECK(unrepaired.size() >= brute.foldedTriangles);
    bool touchesStuck = false;
    for (std::uint32_t t : unrepaired)
        for (std::uint32_t v : m.triangles[t]) touchesStuck |= v == stuck;
    CHECK(touchesStuck);
}

TEST_CASE("repairAndCheckMesh: the last resort takes the candidate that mends the fold", "[surface][mesh]") {
    Mesh m = testing::uvSphere(10, 16, 4.0);
    const auto original = m.vertices;
    const std::uint32_t bad = 45;
    m.vertices[bad] = m.vertices[bad + 1] + 1.5 * (m.vertices[bad + 1] - m.vertices[bad]);
    REQUIRE(checkMesh(m).foldedTriangles > 0);
    FoldRepair repair;
    repair.minCosine = 1e-3;
    repair.pull = [](std::uint32_t, int, Vec3&, const std::vector<std::uint32_t>&) { return false; };

    SECTION("no candidate mends it: nothing moves, and the folds are listed") {
        repair.candidates = [&](std::uint32_t v, const std::vector<std::uint32_t>&, std::vector<Vec3>& out) {
            out.push_back(m.vertices[v] + Vec3(0.0, 0.0, 1e-3));
        };
        std::size_t moved = 9;
        std::vector<std::uint32_t> unrepaired;
        const MeshCheck c = repairAndCheckMesh(m, repair, &moved, &unrepaired);
        CHECK(c.foldedTriangles > 0);
        compare(c, bruteForce(m));
        CHECK(unrepaired.size() >= c.foldedTriangles);
    }
    SECTION("one candidate, among worse ones, is the vertex's true place") {
        repair.candidates = [&](std::uint32_t v, const std::vector<std::uint32_t>&, std::vector<Vec3>& out) {
            out.push_back(m.vertices[v] + Vec3(0.0, 0.0, 1e-3));
            out.push_back(original[v]);
            out.push_back(Vec3(0.0));
        };
        std::size_t moved = 0;
        std::vector<std::uint32_t> unrepaired;
        const MeshCheck c = repairAndCheckMesh(m, repair, &moved, &unrepaired);
        CHECK(c.ok());
        compare(c, bruteForce(m));
        CHECK(unrepaired.empty());
        CHECK(moved >= 1);
        CHECK(m.vertices[bad] == original[bad]);
    }
}
