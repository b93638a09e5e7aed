// The dexel mesher's split cells (surface/detail/split_cells.h): a patch vertex kept on its own
// side of a thin fin's middle, against a position worked out by hand, and the fans of one cell's
// patches that pass through each other.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "surface/detail/crossings.h"
#include "surface/detail/split_cells.h"

using namespace dexelmill;
using detail::SplitCells;

namespace {

constexpr double kFeatureAngle = 0.6;  // ContourOptions' default
/// The cell finEdge's edge bounds, from (0, 0, 0) to (1, 1, 1).
const Vec3 kCellLo(0.0), kCellHi(1.0);

/// Two ends on the y edge through (0.5, 0, 0.5), bounding 0.02 of material from y = 0.40 to 0.42,
/// each in a patch of its own; `joined`: one patch holds both. The upper end's normal is `upper`
/// (+y by default: normals along y, exact when packed).
SplitCells finEdge(bool joined, const Vec3& upper = Vec3(0.0, 1.0, 0.0)) {
    SplitCells cells;
    cells.points = {Vec3(0.5, 0.40, 0.5), Vec3(0.5, 0.42, 0.5)};
    cells.normals = {PackedNormal::pack(Vec3(0.0, -1.0, 0.0)), PackedNormal::pack(upper)};
    cells.edgeEnds = 2;
    cells.partner = {1, 0};
    cells.loopIds = {0, 1};
    cells.loopStart = joined ? std::vector<std::uint32_t>{0, 2} : std::vector<std::uint32_t>{0, 1, 2};
    return cells;
}

}  // namespace

TEST_CASE("split cells: a vertex past a fin's middle is brought back to its own side", "[surface][split]") {
    const SplitCells cells = finEdge(false);
    // The middle is y = 0.41; each side's vertex keeps a quarter of its end's distance from it,
    // 0.0025: the lower side's at y <= 0.4075, the upper side's at y >= 0.4125. Only y moves.
    const Vec3 lower = detail::keepOffFinMiddle(cells, 0, kFeatureAngle, kCellLo, kCellHi, Vec3(0.3, 0.415, 0.7));
    CHECK(lower.x == Approx(0.3));
    CHECK(lower.y == Approx(0.4075).epsilon(1e-9));
    CHECK(lower.z == Approx(0.7));
    const Vec3 upper = detail::keepOffFinMiddle(cells, 1, kFeatureAngle, kCellLo, kCellHi, Vec3(0.6, 0.409, 0.2));
    CHECK(upper.y == Approx(0.4125).epsilon(1e-9));
    CHECK(upper.x == Approx(0.6));
    // A vertex on its own side, on or off its wall, stays where it is.
    CHECK(detail::keepOffFinMiddle(cells, 0, kFeatureAngle, kCellLo, kCellHi, Vec3(0.3, 0.401, 0.7)) == Vec3(0.3, 0.401, 0.7));
    CHECK(detail::keepOffFinMiddle(cells, 1, kFeatureAngle, kCellLo, kCellHi, Vec3(0.3, 0.43, 0.7)) == Vec3(0.3, 0.43, 0.7));
}

TEST_CASE("split cells: a patch that holds both sides of a fin is left alone", "[surface][split]") {
    const SplitCells cells = finEdge(true);
    CHECK(detail::keepOffFinMiddle(cells, 0, kFeatureAngle, kCellLo, kCellHi, Vec3(0.3, 0.415, 0.7)) == Vec3(0.3, 0.415, 0.7));
}

TEST_CASE("split cells: a wedge's vertex is left alone", "[surface][split]") {
    // The upper side leans 53 degrees from the lower's opposite, past the feature angle (34
    // degrees): a wedge, whose middle the stretch's bisector does not follow.
    const SplitCells cells = finEdge(false, Vec3(0.8, 0.6, 0.0));
    CHECK(detail::keepOffFinMiddle(cells, 0, kFeatureAngle, kCellLo, kCellHi, Vec3(0.3, 0.415, 0.7)) == Vec3(0.3, 0.415, 0.7));
}

TEST_CASE("split cells: a vertex brought back from a fin's middle stays in its cell", "[surface][split]") {
    // The upper side's normal leans 0.45 rad from +y toward +z (within the feature angle of the
    // lower side's opposite), so the fin's bisector n, about (0, -0.975, -0.224) for the lower
    // side, slants down: the lower side's vertex near the cell's floor, behind the middle's plane,
    // is moved along it below the floor (the boat-xyzac.ngc vertex 0.099 h below its cell), and
    // its fan would reach into the cell beneath. It stays in the cell, on its floor; x and y keep
    // the move.
    const SplitCells cells = finEdge(false, Vec3(0.0, std::cos(0.45), std::sin(0.45)));
    const Vec3 v(0.3, 0.6, 0.01);
    const Vec3 free = detail::keepOffFinMiddle(cells, 0, kFeatureAngle, Vec3(-10.0), Vec3(10.0), v);
    REQUIRE(free.z < 0.0);
    const Vec3 kept = detail::keepOffFinMiddle(cells, 0, kFeatureAngle, kCellLo, kCellHi, v);
    CHECK(kept.x == Approx(0.3));
    CHECK(kept.y == Approx(free.y));
    CHECK(kept.y < 0.55);
    CHECK(kept.z == 0.0);
}

TEST_CASE("split cells: a vertex on a face a path of its loop crosses is kept off that face", "[surface][split]") {
    // The cell from (0, 0, 0) to (2, 2, 2) (h = 2); kFaceInset is 1e-3 h: 0.002. One loop: two
    // ends on the x edge at y = 0, z = 2 with a face vertex between them on the top face (z = 2),
    // a lens, then crossings on the z edge at x = 2, y = 0 and on the x edge at y = z = 0, its
    // other paths on the face y = 0. Another cuts off the corner (0, 0, 0): a path between two
    // edges on each of the faces x = 0, y = 0 and z = 0.
    const std::vector<Vec3> points = {Vec3(0.8, 0.0, 2.0), Vec3(0.9, 0.6, 2.0), Vec3(1.0, 0.0, 2.0),
                                      Vec3(2.0, 0.0, 1.2), Vec3(0.5, 0.0, 0.0),
                                      Vec3(0.6, 0.0, 0.0), Vec3(0.0, 0.7, 0.0), Vec3(0.0, 0.0, 0.5)};
    const std::uint32_t lens[] = {0, 1, 2, 3, 4}, corner[] = {5, 6, 7};
    const detail::PatchVertexRule::Loop lensLoop{points.data(), nullptr, lens, 5};
    const detail::PatchVertexRule::Loop cornerLoop{points.data(), nullptr, corner, 3};
    const Vec3 lo(0.0);
    // On the top face, and past it: brought 0.002 under it; on the face y = 0 too: 0.002 in.
    CHECK(detail::keepOffPathFaces(lensLoop, lo, 2.0, Vec3(0.85, 0.3, 2.0)) == Vec3(0.85, 0.3, 1.998));
    CHECK(detail::keepOffPathFaces(lensLoop, lo, 2.0, Vec3(0.85, 0.3, 2.1)) == Vec3(0.85, 0.3, 1.998));
    CHECK(detail::keepOffPathFaces(lensLoop, lo, 2.0, Vec3(0.85, 0.0, 1.5)) == Vec3(0.85, 0.002, 1.5));
    // On the face x = 0, and on the edge where it meets y = 0: brought 0.002 in from each; on the
    // top face, which no path of its loop crosses, it stays.
    CHECK(detail::keepOffPathFaces(cornerLoop, lo, 2.0, Vec3(0.0, 0.5, 2.0)) == Vec3(0.002, 0.5, 2.0));
    CHECK(detail::keepOffPathFaces(cornerLoop, lo, 2.0, Vec3(0.0, 0.0, 0.3)) == Vec3(0.002, 0.002, 0.3));
    // Off those faces by more than that, a vertex stays where it is.
    CHECK(detail::keepOffPathFaces(lensLoop, lo, 2.0, Vec3(0.0, 0.3, 1.5)) == Vec3(0.0, 0.3, 1.5));
    CHECK(detail::keepOffPathFaces(cornerLoop, lo, 2.0, Vec3(0.01, 0.5, 0.01)) == Vec3(0.01, 0.5, 0.01));
}

TEST_CASE("split cells: fans of one cell's patches that pass through each other are named, others not",
          "[surface][split]") {
    // Two patches of one cell, each a fan of three triangles round its vertex: the first a flat
    // fan at z = 0.5, the second a fan round (0.5, 0.5, 0.3) whose spokes rise to z = 0.7. The
    // second's triangles pass through the first's plane inside it where `through`; lifted by 0.4
    // they lie wholly above it. A third patch, in another cell, crosses the first but is not its
    // cell's: only patches of one cell are compared.
    const auto make = [](bool through) {
        Mesh mesh;
        const double lift = through ? 0.0 : 0.4;
        mesh.vertices = {Vec3(0.5, 0.5, 0.5), Vec3(0.1, 0.1, 0.5), Vec3(0.9, 0.2, 0.5), Vec3(0.4, 0.9, 0.5),
                         Vec3(0.5, 0.5, 0.3 + lift), Vec3(0.2, 0.3, 0.7 + lift), Vec3(0.8, 0.3, 0.7 + lift),
                         Vec3(0.5, 0.8, 0.7 + lift), Vec3(0.5, 0.5, 0.2), Vec3(0.3, 0.3, 0.8), Vec3(0.7, 0.4, 0.8)};
        mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {4, 5, 6}, {4, 6, 7}, {4, 7, 5}, {8, 9, 10}};
        SplitCells cells;
        cells.cells = {detail::GridPoint{0, 0, 0}, detail::GridPoint{5, 0, 0}};
        cells.cellPatchStart = {0, 2, 3};
        cells.loopStart = {0, 3, 6, 7};  // loops of 3, 3 and 1 ends: fans of as many triangles
        cells.patchCell = {cells.cells[0], cells.cells[0], cells.cells[1]};
        return std::make_pair(mesh, cells);
    };
    const std::vector<std::uint32_t> first{0, 3, 6};
    const auto [crossed, crossedCells] = make(true);
    // The third patch's triangle does cross the first fan, so its absence below is the cell rule's.
    const auto corners = [&](std::size_t t) {
        const auto& tri = crossed.triangles[t];
        return std::array<Vec3, 3>{crossed.vertices[tri[0]], crossed.vertices[tri[1]], crossed.vertices[tri[2]]};
    };
    bool thirdCrossesFirst = false;
    for (std::size_t t = 0; t < 3; ++t)
        thirdCrossesFirst |= detail::trianglesCross(crossed.triangles[t], corners(t), crossed.triangles[6], corners(6), 1e-9);
    REQUIRE(thirdCrossesFirst);
    const std::vector<std::uint32_t> found = detail::crossingPatchTriangles(crossedCells, crossed, first, 1e-9);
    // Each of the second fan's triangles runs from below the plane (its vertex) to above it (its
    // far edge) over the first fan, so it crosses at least one of the first's triangles.
    REQUIRE_FALSE(found.empty());
    REQUIRE(found.size() % 2 == 0);
    for (std::size_t i = 0; i < found.size(); i += 2) {
        CHECK(found[i] < 3);
        CHECK(found[i + 1] >= 3);
        CHECK(found[i + 1] < 6);
    }
    for (std::uint32_t t = 3; t < 6; ++t) CHECK(std::count(found.begin(), found.end(), t) > 0);
    const auto [apart, apartCells] = make(false);
    CHECK(detail::crossingPatchTriangles(apartCells, apart, first, 1e-9).empty());
}
