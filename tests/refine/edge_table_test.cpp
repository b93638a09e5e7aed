// The refinement's edge table against a brute-force count of each undirected edge's corner slots,
// on closed meshes, subsets of them (boundaries), and meshes with non-manifold or repeated corners.
#include <catch2/catch.hpp>

#include <algorithm>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "refine/detail/edge_table.h"

using namespace dexelmill;
using detail::kNoTriangle;

namespace {

/// An octahedron: a closed mesh with every edge shared by two triangles in opposite directions.
Mesh octahedron() {
    Mesh m;
    m.vertices = {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0, 0, 1), Vec3(0, 0, -1)};
    m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    return m;
}

/// Checks `e` against the slots of `triangles` counted by brute force: every slot of one undirected
/// edge maps to one edge with those ends, and the edge keeps its two triangles exactly when it
/// has one slot each way.
void compare(const Mesh& m, const std::vector<std::uint32_t>& triangles, const detail::EdgeTable& e) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::size_t>> slots;
    for (std::size_t i = 0; i < triangles.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = m.triangles[triangles[i]][k], b = m.triangles[triangles[i]][(k + 1) % 3];
            slots[{std::min(a, b), std::max(a, b)}].push_back(3 * i + std::size_t(k));
        }
    std::size_t expectedEdges = 0;
    for (const auto& [ends, list] : slots) {
        const std::uint32_t a = ends.first, b = ends.second;
        std::size_t up = 0, down = 0;
        for (std::size_t s : list) (m.triangles[triangles[s / 3]][s % 3] == a ? up : down) += 1;
        const bool pair = a != b && up == 1 && down == 1;
        if (pair) {
            ++expectedEdges;
            const std::uint32_t id = e.edgeOf[list[0]];
            REQUIRE(e.edgeOf[list[1]] == id);
            CHECK(e.ends[id] == std::array<std::uint32_t, 2>{a, b});
            std::array<std::uint32_t, 2> t = e.triangles[id];
            std::sort(t.begin(), t.end());
            CHECK(t == std::array<std::uint32_t, 2>{std::uint32_t(std::min(list[0], list[1]) / 3),
                                                    std::uint32_t(std::max(list[0], list[1]) / 3)});
        } else {
            for (std::size_t s : list) CHECK(e.triangles[e.edgeOf[s]][0] == kNoTriangle);
        }
    }
    std::size_t paired = 0;
    for (const auto& t : e.triangles) paired += t[0] != kNoTriangle;
    CHECK(paired == expectedEdges);
}

std::vector<std::uint32_t> all(const Mesh& m) {
    std::vector<std::uint32_t> t(m.triangles.size());
    for (std::uint32_t i = 0; i < t.size(); ++i) t[i] = i;
    return t;
}

}  // namespace

TEST_CASE("edge table: a closed mesh pairs every edge", "[refine]") {
    const Mesh m = octahedron();
    const detail::EdgeTable e = detail::buildEdges(m, all(m));
    CHECK(e.ends.size() == 12);
    compare(m, all(m), e);
}

TEST_CASE("edge table: a subset's border edges keep no triangles", "[refine]") {
    const Mesh m = octahedron();
    std::mt19937 rng(3);
    for (int round = 0; round < 20; ++round) {
        std::vector<std::uint32_t> some;
        for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
            if (rng() % 2) some.push_back(t);
        const detail::EdgeTable e = detail::buildEdges(m, some);
        compare(m, some, e);
    }
}

TEST_CASE("edge table: non-manifold edges and repeated corners are never paired", "[refine]") {
    Mesh m = octahedron();
    // A third triangle on edge 0-2, either way, and a triangle with a repeated corner.
    m.triangles.push_back({0, 2, 5});
    m.triangles.push_back({2, 0, 1});
    m.triangles.push_back({3, 3, 4});
    const detail::EdgeTable e = detail::buildEdges(m, all(m));
    compare(m, all(m), e);
}
