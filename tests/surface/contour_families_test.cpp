// The dexel mesher on stocks whose three dexel families disagree grossly: a family left empty
// where the others hold a box, as an open stock mesh casts it. The level set's majority vote then
// changes sign where no family has an end, outside the band of leaves the rebuild makes.
#include <catch2/catch.hpp>

#include <cstdint>
#include <string>

#include "dexelmill/error.h"
#include "dexelmill/surface/contour.h"
#include "dexelmill/surface/levelset.h"
#include "dexelmill/surface/levelset_vdb.h"
#include "dexelmill/surface/voxelize.h"

using namespace dexelmill;

namespace {

const Box kBox{Vec3(-10.0, -10.0, -15.0), Vec3(10.0, 10.0, 0.0)};

/// A box stock with the dexels of family `empty` cleared where `clear(b, c)` says (b, c: the
/// dexel's world coordinates across its axis, in the family's index order).
template <class F>
TriDexelStock disagreeingBox(double h, Axis empty, F&& clear) {
    TriDexelStock stock = TriDexelStock::fromBox(kBox, h);
    DexelFamily& fam = stock.family(empty);
    const Lattice& lat = stock.lattice();
    for (int ic = 0; ic < fam.nc(); ++ic)
        for (int ib = 0; ib < fam.nb(); ++ib)
            if (clear(lat.coord(fam.axisB(), ib), lat.coord(fam.axisC(), ic))) fam.setSegments(ib, ic, nullptr, 0);
    return stock;
}

/// kBox as 12 outward triangles, the last `missing` of them left out (the top face's come last).
Mesh boxMesh(int missing) {
    Mesh m;
    for (int i = 0; i < 8; ++i)
        m.vertices.emplace_back(i & 1 ? kBox.hi.x : kBox.lo.x, i & 2 ? kBox.hi.y : kBox.lo.y, i & 4 ? kBox.hi.z : kBox.lo.z);
    const std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}, {4, 5, 7, 6}};
    for (const auto& q : quads) {
        m.triangles.push_back({q[0], q[1], q[2]});
        m.triangles.push_back({q[0], q[2], q[3]});
    }
    m.triangles.resize(m.triangles.size() - std::size_t(missing));
    return m;
}

/// Contours the stock: the mesh must be closed, or the error must say that the families disagree
/// and where. Returns whether it threw.
bool closedOrError(const TriDexelStock& stock) {
    const LevelSet ls = rebuildLevelSet(stock);
    try {
        const Mesh mesh = contourStock(ls, stock);
        CHECK(checkMesh(mesh).closedManifold());
        return false;
    } catch (const Error& e) {
        const std::string what = e.what();
        INFO(what);
        CHECK(what.find("families disagree") != std::string::npos);
        CHECK(what.find(") mm") != std::string::npos);
        return true;
    }
}

}  // namespace

TEST_CASE("contour: families that disagree give a closed mesh or an error, never a crash", "[surface][contour]") {
    int errors = 0, meshes = 0;
    for (double h : {0.5, 0.25, 1.0}) {
        for (Axis a : {Axis::X, Axis::Y, Axis::Z}) {
            for (int region = 0; region < 2; ++region) {
                // The whole family, or its dexels under one half of the box.
                INFO("h " << h << ", family " << index(a) << " emptied " << (region == 0 ? "whole" : "in half"));
                const TriDexelStock stock = disagreeingBox(h, a, [&](double b, double c) { return region == 0 || b + c < 0.0; });
                (closedOrError(stock) ? errors : meshes) += 1;
            }
        }
    }
    // Both outcomes occur: which one depends on where the rebuild's band has holes.
    CHECK(errors > 0);
    CHECK(meshes > 0);
}

TEST_CASE("contour: a stock cast from a box mesh missing a triangle gives a closed mesh or an error", "[surface][contour]") {
    // Its z dexels under the hole cross the mesh once: the z family loses material there that the
    // x and y families keep.
    for (double h : {0.5, 1.0}) {
        INFO("h " << h);
        MeshCastStats cast;
        const TriDexelStock stock = stockFromMesh(boxMesh(1), Lattice::fromBox(kBox, h), FamilySet::all(), &cast);
        CHECK(cast.unpairedDexels > 0);
        CHECK(stock.volume(Axis::Z) < stock.volume(Axis::X) - 1.0);
        closedOrError(stock);
    }
}

TEST_CASE("contour: a sign change between tiles beside the leaves is an error, not a hole", "[surface][contour]") {
    // A level set that changes sign between tiles, as the rebuild of families that disagree makes
    // one, here made by hand: far above the stock an empty leaf, and below it a tile of material.
    // The index holds the blocks just below the leaf, whose cells mesh the tile's top and the top
    // of its sides and ask for no crossing elsewhere; the cells of its sides further down lie in
    // blocks it lacks. The mesh would have a hole there.
    const TriDexelStock stock = TriDexelStock::fromBox(Box{Vec3(0.0), Vec3(16.0)}, 1.0);
    const LevelSet rebuilt = rebuildLevelSet(stock);
    openvdb::FloatGrid::Ptr grid = gridOf(rebuilt)->deepCopy();
    const openvdb::Coord leaf(0, 0, 64), below(0, 0, 56);
    REQUIRE(grid->tree().getValue(leaf) > 0.0f);
    grid->tree().touchLeaf(leaf);
    grid->tree().addTile(1, below, -grid->background(), false);
    const LevelSet ls = levelSetFromGrid(grid);
    try {
        const Mesh mesh = contourStock(ls, stock);
        FAIL("a mesh with " << checkMesh(mesh).boundaryEdges << " open edges");
    } catch (const Error& e) {
        INFO(e.what());
        CHECK(std::string(e.what()).find("changes sign outside its band") != std::string::npos);
    }
}
