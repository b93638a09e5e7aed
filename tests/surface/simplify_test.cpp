// collapseShortEdges against oracles that share no code with it: a sphere whose edges were split
// next to an end must come back triangle for triangle, and on jittered spheres every result is
// checked edge by edge and vertex normal by vertex normal, here (fixed seeds).
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "dexelmill/surface/mesh.h"
#include "dexelmill/surface/simplify.h"
#include "support/uv_sphere.h"

using namespace dexelmill;

namespace {

using Corners = std::array<Vec3, 3>;

/// A triangle by its corners' positions, turned to start at its least corner: meshes compare by
/// these whatever their indices.
Corners canonical(const Mesh& m, const Mesh::Triangle& t) {
    Corners c{m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]};
    const auto less = [](const Vec3& a, const Vec3& b) {
        return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
    };
    std::rotate(c.begin(), std::min_element(c.begin(), c.end(), less), c.end());
    return c;
}

std::multiset<std::array<double, 9>> triangleSet(const Mesh& m) {
    std::multiset<std::array<double, 9>> out;
    for (const Mesh::Triangle& t : m.triangles) {
        const Corners c = canonical(m, t);
        out.insert({c[0].x, c[0].y, c[0].z, c[1].x, c[1].y, c[1].z, c[2].x, c[2].y, c[2].z});
    }
    return out;
}

/// What the oracle sees: edges used other than once each way, folded triangles (facing against
/// the sum of their corners' unit area-weighted normals) and zero-area ones.
struct Oracle {
    std::size_t badEdges = 0, folded = 0, flat = 0;
};

Oracle oracle(const Mesh& m) {
    Oracle r;
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
    std::vector<Vec3> normal(m.vertices.size(), Vec3(0.0));
    for (const Mesh::Triangle& t : m.triangles) {
        const Vec3 n = glm::cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]);
        for (int k = 0; k < 3; ++k) {
            ++directed[{t[k], t[(k + 1) % 3]}];
            normal[t[k]] += n;
        }
        if (glm::length(n) == 0.0) ++r.flat;
    }
    for (const auto& [edge, count] : directed) {
        const auto back = directed.find({edge.second, edge.first});
        if (count != 1 || back == directed.end() || back->second != 1) ++r.badEdges;
    }
    for (Vec3& n : normal)
        if (glm::length(n) > 0.0) n = glm::normalize(n);
    for (const Mesh::Triangle& t : m.triangles) {
        const Vec3 n = glm::cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]);
        if (glm::dot(n, normal[t[0]] + normal[t[1]] + normal[t[2]]) < 0.0) ++r.folded;
    }
    return r;
}

/// Splits edge a-b of both its triangles at p (appended), as refinement does.
void splitEdge(Mesh& m, std::uint32_t a, std::uint32_t b, const Vec3& p) {
    const std::uint32_t s = std::uint32_t(m.vertices.size());
    m.vertices.push_back(p);
    const std::size_t n = m.triangles.size();
    for (std::size_t t = 0; t < n; ++t)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t x = m.triangles[t][k], y = m.triangles[t][(k + 1) % 3], z = m.triangles[t][(k + 2) % 3];
            if ((x == a && y == b) || (x == b && y == a)) {
                m.triangles[t] = {x, s, z};
                m.triangles.push_back({s, y, z});
                break;
            }
        }
}

}  // namespace

TEST_CASE("collapsing short edges: splits next to a vertex, crumpled, come out again", "[surface][simplify]") {
    // On a sphere of radius 10 (edges 1.3 to 2.6), edges are split 0.001 to 0.02 along from an
    // end and up to 0.017 off it in any direction: the pieces at that end face every way, as a
    // refinement split next to a crossing did on bear. Collapsing the edges shorter than 0.05
    // takes each split point back into its end, and leaves the sphere as it was.
    for (unsigned seed : {1u, 2u, 3u}) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<double> unit(0.0, 1.0);
        const Mesh original = testing::uvSphere(12, 24, 10.0);
        Mesh m = original;
        std::vector<char> used(original.vertices.size(), 0);
        std::size_t splits = 0;
        for (int attempt = 0; attempt < 400 && splits < 40; ++attempt) {
            const Mesh::Triangle t = original.triangles[std::size_t(rng() % original.triangles.size())];
            const int k = int(rng() % 3);
            const std::uint32_t a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
            // The triangle across a-b: its third corner.
            std::uint32_t d = a;
            for (const Mesh::Triangle& o : original.triangles)
                for (int j = 0; j < 3; ++j)
                    if (o[j] == b && o[(j + 1) % 3] == a) d = o[(j + 2) % 3];
            if (used[a] || used[b] || used[c] || used[d]) continue;
            used[a] = used[b] = used[c] = used[d] = 1;
            const Vec3 off(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
            const Vec3 p = original.vertices[a] + (0.001 + 0.019 * unit(rng)) / glm::length(original.vertices[b] - original.vertices[a]) *
                                                      (original.vertices[b] - original.vertices[a]) +
                           0.02 * off;
            splitEdge(m, a, b, p);
            ++splits;
        }
        REQUIRE(splits >= 20);
        const Oracle before = oracle(m);
        INFO("seed " << seed << ": " << splits << " splits, " << before.folded << " folded before");
        REQUIRE(before.badEdges == 0);
        CHECK(collapseShortEdges(m, 0.05) == splits);
        CHECK(m.vertices.size() == original.vertices.size());
        CHECK(triangleSet(m) == triangleSet(original));
    }
}

TEST_CASE("collapsing short edges keeps a mesh closed, unfolded and on its vertices", "[surface][simplify]") {
    // Jittered spheres, with lengths up to twice their edges: many collapses are tried, and those
    // that would fold or open the mesh must be refused. What is left is checked by the oracle, and
    // its vertices must be the input's (a collapse moves none).
    for (unsigned seed : {1u, 2u, 3u, 4u}) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<double> jitter(-0.15, 0.15);
        Mesh m = testing::uvSphere(8 + int(rng() % 6), 10 + int(rng() % 10), 3.0);
        for (Vec3& v : m.vertices) v += Vec3(jitter(rng), jitter(rng), jitter(rng));
        const Mesh input = m;
        REQUIRE(oracle(input).folded == 0);
        const double length = 0.5 + 1.5 * double(seed) / 4.0;
        const std::size_t collapsed = collapseShortEdges(m, length);
        const Oracle after = oracle(m);
        INFO("seed " << seed << ", length " << length << ": " << collapsed << " collapsed");
        CHECK(collapsed > 0);
        CHECK(after.badEdges == 0);
        CHECK(after.folded == 0);
        CHECK(after.flat == 0);
        CHECK(m.vertices.size() + collapsed == input.vertices.size());
        std::set<std::array<double, 3>> inputPoints;
        for (const Vec3& v : input.vertices) inputPoints.insert({v.x, v.y, v.z});
        for (const Vec3& v : m.vertices) CHECK(inputPoints.count({v.x, v.y, v.z}) == 1);
        // Every vertex collapsed away lies within the length of one kept.
        std::size_t far = 0;
        for (const Vec3& v : input.vertices) {
            double nearest = 1e300;
            for (const Vec3& w : m.vertices) nearest = std::min(nearest, glm::length(v - w));
            if (!(nearest < length)) ++far;
        }
        CHECK(far == 0);
    }
}

TEST_CASE("collapsing short edges: none shorter, or none at all, changes nothing", "[surface][simplify]") {
    const Mesh original = testing::uvSphere(8, 12, 2.0);
    Mesh m = original;
    CHECK(collapseShortEdges(m, 0.01) == 0);
    CHECK(collapseShortEdges(m, 0.0) == 0);
    CHECK(collapseShortEdges(m, -1.0) == 0);
    CHECK(triangleSet(m) == triangleSet(original));
    Mesh empty;
    CHECK(collapseShortEdges(empty, 1.0) == 0);
}

TEST_CASE("collapsing short edges: a collapse that would fold a triangle is refused", "[surface][simplify]") {
    // A double pyramid: a flat top fanned round u at the origin over the ring r0 .. r4, and a
    // bottom fanned round (0, 0, -1). Its one short edge is u-r0 (0.2). Moved to r0, u's triangle
    // (u, r1, r2) would face down: r0 lies across the line r1-r2 from u. With r1 moved so that it
    // does not, the same collapse is made.
    for (const bool crosses : {true, false}) {
        const std::vector<Vec3> ring{Vec3(0.2, 0.0, 0.0), Vec3(crosses ? 0.1 : 0.3, 0.3, 0.0), Vec3(0.11, 1.0, 0.0),
                                     Vec3(-1.0, 0.0, 0.0), Vec3(0.2, -1.0, 0.0)};
        Mesh m;
        m.vertices = {ring[0], ring[1], ring[2], ring[3], ring[4], Vec3(0.0, 0.0, -1.0), Vec3(0.0, 0.0, 0.0)};
        const std::uint32_t bottom = 5, u = 6;
        for (std::uint32_t k = 0; k < 5; ++k) {
            m.triangles.push_back({u, k, (k + 1) % 5});
            m.triangles.push_back({bottom, (k + 1) % 5, k});
        }
        const Oracle before = oracle(m);
        REQUIRE(before.badEdges == 0);
        REQUIRE(before.folded == 0);
        INFO((crosses ? "r0 across r1-r2 from u" : "r0 on u's side of r1-r2"));
        const double r1r2 = glm::cross(ring[1] - ring[0], ring[2] - ring[0]).z;
        REQUIRE((r1r2 < 0.0) == crosses);  // (r0, r1, r2) faces down
        const std::size_t collapsed = collapseShortEdges(m, 0.21);
        CHECK(collapsed == (crosses ? 0u : 1u));
        CHECK(oracle(m).folded == 0);
        CHECK(oracle(m).badEdges == 0);
    }
}
