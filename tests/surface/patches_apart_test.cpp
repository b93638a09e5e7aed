// The table path's patches of one cell moved apart (surface/detail/patches_apart.h), on a cell of a
// real fin, judged by the tests' own self-intersection count (support/self_intersection.h), which
// shares no code with the library.
#include <catch2/catch.hpp>

#include <vector>

#include "support/self_intersection.h"
#include "surface/detail/patches_apart.h"

using namespace dexelmill;

namespace {

/// The cell at (7.5, 7.5, 1.5) of two ball plunges of radius 5 h (h = 1) whose surfaces pass
/// 0.0095 h apart at (9.21, 9.42, 1.08) (contour_test.cpp, "the patches of a fin's cell that the
/// face rule cut apart"): vertex 0 and its loop 2-6, round three corners, and vertex 1 and its
/// loop 7-9, the corner (8.5, 8.5, 1.5) cut off, as pass 3 fitted them; their fans cross.
Mesh finCell() {
    Mesh m;
    m.vertices = {{8.36643672, 8.499, 1.57381607}, {8.36726552, 8.44851271, 1.55947849},
                  {8.23367572, 7.5, 1.5},          {7.5, 8.20109344, 1.5},
                  {7.5, 8.5, 1.99159884},          {8.36643672, 8.5, 2.5},
                  {8.07296014, 7.5, 2.5},          {8.00163984, 8.5, 1.5},
                  {8.5, 8.40902638, 1.5},          {8.5, 8.5, 1.63969827}};
    return m;
}

std::vector<detail::SharedPatch> patchesOf() {
    std::vector<detail::SharedPatch> p(2);
    p[0].vertex = 0;
    p[0].len = 5;
    for (int i = 0; i < 5; ++i) p[0].loop[i] = std::uint32_t(2 + i);
    p[1].vertex = 1;
    p[1].len = 3;
    for (int i = 0; i < 3; ++i) p[1].loop[i] = std::uint32_t(7 + i);
    return p;
}

/// The mesh's fans.
void addFans(Mesh& m, const std::vector<detail::SharedPatch>& patches) {
    m.triangles.clear();
    for (const detail::SharedPatch& s : patches)
        for (int i = 0; i < s.len; ++i) m.triangles.push_back({s.vertex, s.loop[i], s.loop[(i + 1) % s.len]});
}

Vec3 massOf(const Mesh& m, const detail::SharedPatch& s) {
    Vec3 sum(0.0);
    for (int i = 0; i < s.len; ++i) sum += m.vertices[s.loop[i]];
    return sum / double(s.len);
}

}  // namespace

TEST_CASE("patches apart: a fin's cell whose fans cross has its vertices moved towards their mass points until apart",
          "[surface][contour]") {
    Mesh m = finCell();
    const std::vector<detail::SharedPatch> patches = patchesOf();
    addFans(m, patches);
    REQUIRE(testing::countSelfIntersections(m).pairs > 0);
    const Mesh before = m;
    const detail::PatchesApart apart =
        detail::keepPatchesApart(patches.data(), 2, m.vertices.data(), 1e-9);
    CHECK(apart.moved >= 1);
    CHECK(apart.leftCrossing == 0);
    CHECK(testing::countSelfIntersections(m).pairs == 0);
    for (const detail::SharedPatch& s : patches) {
        // On the segment from where it was fitted to its loop's mass point: only the vertex moved,
        // and within its crossings' box, which holds both ends.
        const Vec3 from = before.vertices[s.vertex], to = massOf(m, s), at = m.vertices[s.vertex];
        const double t = glm::dot(at - from, to - from) / glm::dot(to - from, to - from);
        CHECK(t >= 0.0);
        CHECK(t <= 1.0);
        CHECK(glm::length(at - (from + t * (to - from))) <= 1e-12);
    }
    for (std::uint32_t v = 2; v < m.vertices.size(); ++v) CHECK(m.vertices[v] == before.vertices[v]);
}

TEST_CASE("patches apart: fans that do not cross are left as they are", "[surface][contour]") {
    Mesh m = finCell();
    const std::vector<detail::SharedPatch> patches = patchesOf();
    // Each vertex at its loop's mass point: each fan lies in its loop's hull, and those are apart.
    for (const detail::SharedPatch& s : patches) m.vertices[s.vertex] = massOf(m, s);
    addFans(m, patches);
    REQUIRE(testing::countSelfIntersections(m).pairs == 0);
    const Mesh before = m;
    const detail::PatchesApart apart =
        detail::keepPatchesApart(patches.data(), 2, m.vertices.data(), 1e-9);
    CHECK(apart.moved == 0);
    CHECK(apart.leftCrossing == 0);
    CHECK(m.vertices == before.vertices);
}

TEST_CASE(
    "patches apart: fans that cross where the loops' hulls meet are left as they are, and counted",
    "[surface][contour]") {
    // Two flat loops through each other: one in the plane z = 0.5, one in x = 0.5, each rectangle
    // passing through the other's inside, so no plane lies between them.
    Mesh m;
    m.vertices = {{0.5, 0.5, 0.5}, {0.5, 0.45, 0.55}, {0.0, 0.2, 0.5}, {1.0, 0.2, 0.5},
                  {1.0, 0.8, 0.5}, {0.0, 0.8, 0.5},   {0.5, 0.3, 0.1}, {0.5, 0.7, 0.1},
                  {0.5, 0.7, 1.0}, {0.5, 0.3, 1.0}};
    std::vector<detail::SharedPatch> patches(2);
    for (int k = 0; k < 2; ++k) {
        patches[std::size_t(k)].vertex = std::uint32_t(k);
        patches[std::size_t(k)].len = 4;
        for (int i = 0; i < 4; ++i) patches[std::size_t(k)].loop[i] = std::uint32_t(2 + 4 * k + i);
    }
    addFans(m, patches);
    REQUIRE(testing::countSelfIntersections(m).pairs > 0);
    const Mesh before = m;
    const detail::PatchesApart apart =
        detail::keepPatchesApart(patches.data(), 2, m.vertices.data(), 1e-9);
    CHECK(apart.moved == 0);
    CHECK(apart.leftCrossing == 1);
    CHECK(m.vertices == before.vertices);
}
