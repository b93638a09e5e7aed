#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <set>
#include <utility>

#include "dexelmill/error.h"
#include "dexelmill/surface/levelset.h"
#include "support/analytic_parts.h"

using namespace dexelmill;
using dexelmill::testing::Cutter;

namespace {

// 64^3 lattice: a 32 mm cube at h = 0.5 mm, its corner off the origin so that the transform's
// translation matters.
const Box kStockBox{Vec3(-10.0, 5.0, 2.0), Vec3(22.0, 37.0, 34.0)};
constexpr double kH = 0.5;
const Vec3 kC = Vec3(6.0, 21.0, 18.0);  // the box centre

struct Accuracy {
    double maxError = 0.0, rmsError = 0.0;
    std::size_t measured = 0;
};

Accuracy measureVertices(const Mesh& mesh, const testing::PartSurfaces& part, double band) {
    Accuracy acc;
    double sum2 = 0.0;
    for (const Vec3& v : mesh.vertices) {
        const auto [d, nearFeature] = part.measure(v, band);
        if (nearFeature) continue;
        acc.maxError = std::max(acc.maxError, d);
        sum2 += d * d;
        ++acc.measured;
    }
    acc.rmsError = acc.measured ? std::sqrt(sum2 / acc.measured) : 0.0;
    return acc;
}

/// Carves, rebuilds, meshes and checks one part against the criteria.
void checkPart(const std::vector<Cutter>& cuts) {
    TriDexelStock stock = TriDexelStock::fromBox(kStockBox, kH);
    for (const Cutter& c : cuts) testing::carve(stock, c);
    const LevelSet ls = rebuildLevelSet(stock, {3, FamilySet::all(), "test", std::nullopt});
    const Mesh mesh = meshLevelSet(ls);
    const MeshCheck check = checkMesh(mesh);
    INFO("vertices " << check.vertexCount << " triangles " << check.triangleCount);
    INFO("boundary " << check.boundaryEdges << " non-manifold " << check.nonManifoldEdges
                     << " misoriented " << check.misorientedEdges << " degenerate "
                     << check.degenerateTriangles);
    CHECK(check.closedManifold());
    CHECK(check.degenerateTriangles == 0);

    const double dexelVolume = stock.volume(Axis::Z);
    INFO("mesh volume " << check.signedVolume << " dexel volume " << dexelVolume);
    CHECK(std::abs(check.signedVolume - dexelVolume) <= 0.005 * dexelVolume);

    const testing::PartSurfaces part(kStockBox, cuts);
    const Accuracy acc = measureVertices(mesh, part, 2.0 * kH);
    INFO("max " << acc.maxError / kH << " h, rms " << acc.rmsError / kH << " h over "
                << acc.measured << " vertices");
    CHECK(acc.measured > mesh.vertices.size() / 2);
    CHECK(acc.maxError <= 0.1 * kH);
    CHECK(acc.rmsError <= 0.02 * kH);
}

/// floor(i / 8): the 8^3 block of grid index i.
int blockOf8(int i) { return i >= 0 ? i / 8 : -((7 - i) / 8); }

/// The estimate of method.md section 7 worked out per voxel of the stock's lattice (and 4 points
/// around it) with no block marks, binary searches or early outs: each family's dexel through the
/// voxel scanned end to end. Returns the active voxels the oracle finds (the grid must hold the
/// same number) and how many voxels it compared. With an index offset given, the grid must also
/// have a leaf exactly at each 8^3 block of grid indexes (lattice point + offset) that holds an
/// active voxel.
std::pair<std::size_t, std::size_t> checkAgainstBruteForce(const TriDexelStock& stock,
                                                           std::optional<std::array<int, 3>> offset = std::nullopt) {
    const int halfWidth = 3;
    const LevelSet ls = rebuildLevelSet(stock, {halfWidth, FamilySet::all(), "test", offset});
    std::set<std::array<int, 3>> activeBlocks;
    const double h = stock.lattice().h;
    const double width = halfWidth * h;
    // Crossings beyond this along an axis are left out (the rebuild's cut-off: twice the reach
    // sqrt(3) w of a band point to its nearest crossing).
    const double cutoff = 2.0 * std::sqrt(3.0) * width;
    // The rebuild sums in float, the oracle in double.
    constexpr double kFloatSum = 1e-5;
    const Lattice& lat = stock.lattice();
    std::size_t active = 0, compared = 0;
    for (int i = -4; i < lat.n[0] + 4; ++i)
        for (int j = -4; j < lat.n[1] + 4; ++j)
            for (int k = -4; k < lat.n[2] + 4; ++k) {
                const int p[3] = {i, j, k};
                double invSq = 0.0;
                int votes = 0;
                for (int a = 0; a < 3; ++a) {
                    const int b = (a + 1) % 3, c = (a + 2) % 3;
                    const DexelFamily& fam = stock.family(axisFromIndex(a));
                    if (p[b] < 0 || p[b] >= fam.nb() || p[c] < 0 || p[c] >= fam.nc()) continue;
                    const double t = (p[a] + 0.5) * h;
                    double nearest = std::numeric_limits<double>::infinity();
                    bool in = false;
                    for (const Segment& sg : fam.segments(p[b], p[c])) {
                        in = in || (sg.lo <= t && t < sg.hi);
                        nearest = std::min({nearest, std::abs(t - double(sg.lo)), std::abs(t - double(sg.hi))});
                    }
                    votes += in;
                    const double d = std::max(nearest, 1e-6 * h);
                    if (d <= cutoff) invSq += 1.0 / (d * d);
                }
                const double s = 2 * votes > 3 ? -1.0 : 1.0;
                const double w2 = 1.0 / (width * width);
                if (std::abs(invSq - w2) <= kFloatSum * w2) continue;  // on the band's edge
                const double expected = invSq > w2 ? s / std::sqrt(invSq) : s * width;
                active += invSq > w2;
                if (offset && invSq > w2)
                    activeBlocks.insert({blockOf8(i + (*offset)[0]), blockOf8(j + (*offset)[1]), blockOf8(k + (*offset)[2])});
                ++compared;
                INFO("voxel (" << i << ", " << j << ", " << k << ")");
                REQUIRE(std::abs(ls.voxelValue(i, j, k) - expected) <= kFloatSum * std::abs(expected));
            }
    CHECK(active == ls.activeVoxelCount());
    // Points on the band's edge were skipped: none of them may be all that holds a leaf.
    if (offset) CHECK(ls.leafCount() == activeBlocks.size());
    return {active, compared};
}

}  // namespace

TEST_CASE("rebuild: grid convention, class, name and metadata", "[surface]") {
    const TriDexelStock stock = TriDexelStock::fromBox(kStockBox, kH);
    const LevelSet ls = rebuildLevelSet(stock, {3, FamilySet::all(), "box", std::nullopt});
    CHECK(ls.voxelSize() == Approx(kH));
    CHECK(ls.halfWidth() == Approx(3.0));
    CHECK(ls.source() == "box");
    REQUIRE(ls.lattice().has_value());
    CHECK(ls.lattice()->n == stock.lattice().n);
    // voxelValue takes lattice indexes: point 0 lies h/2 inside the box face, point -1 h/2
    // outside, and both are exact distances to the plane.
    CHECK(ls.voxelValue(0, 30, 30) == Approx(-0.5 * kH));
    CHECK(ls.voxelValue(-1, 30, 30) == Approx(0.5 * kH));
    CHECK(ls.voxelValue(2, 30, 30) == Approx(-2.5 * kH));
    CHECK(ls.voxelValue(30, 30, 30) == Approx(-3.0 * kH));  // interior background
    CHECK(ls.voxelValue(-10, 30, 30) == Approx(3.0 * kH));   // exterior background
    // Near a box corner the three axis distances combine: h/2 from each face.
    CHECK(ls.voxelValue(0, 0, 0) == Approx(-0.5 * kH / std::sqrt(3.0)));
    CHECK(ls.valueAt(stock.lattice().point(10, 0, 30)) == Approx(-0.5 * kH));
    CHECK_THROWS_AS(rebuildLevelSet(stock, {2, FamilySet::all(), "", std::nullopt}), Error);
}

TEST_CASE("rebuild: every voxel holds the axis-distance estimate, by brute force", "[surface]") {
    TriDexelStock stock = TriDexelStock::fromBox(kStockBox, kH);
    testing::carve(stock, testing::sphere(kC + Vec3(0.0, 0.0, 12.0), 10.0));
    testing::carve(stock, testing::torus(kC + Vec3(0.0, 0.0, -4.0), Vec3(0.2, -0.1, 1.0), 9.0, 4.0));
    const auto [active, compared] = checkAgainstBruteForce(stock);
    CHECK(active > 10000);
    CHECK(compared > 300000);
}

TEST_CASE("rebuild: any index offset gives the same values, and leaves exactly where the band is", "[surface]") {
    // A pocket's flat floor and walls across all three axes, a sphere and a torus: offsets 0 and
    // 7 on every axis, and random ones (fixed seed).
    TriDexelStock stock = TriDexelStock::fromBox(kStockBox, kH);
    testing::carve(stock, testing::boxCutter({kC + Vec3(-9.3, -7.1, 4.2), kC + Vec3(8.8, 6.4, 20.0)}));
    testing::carve(stock, testing::sphere(kC + Vec3(4.0, -3.0, 5.0), 4.0));
    testing::carve(stock, testing::torus(kC + Vec3(0.0, 0.0, -6.0), Vec3(0.2, -0.1, 1.0), 9.0, 4.0));
    std::mt19937 rng(21);
    std::uniform_int_distribution<int> phase(0, 7);
    for (const std::array<int, 3>& offset :
         {std::array<int, 3>{0, 0, 0}, std::array<int, 3>{7, 7, 7}, std::array<int, 3>{phase(rng), phase(rng), phase(rng)}}) {
        INFO("offset " << offset[0] << ", " << offset[1] << ", " << offset[2]);
        const auto [active, compared] = checkAgainstBruteForce(stock, offset);
        CHECK(active > 10000);
        CHECK(compared > 300000);
    }
    CHECK_THROWS_AS(rebuildLevelSet(stock, {3, FamilySet::all(), "", std::array<int, 3>{0, 8, 0}}), Error);
    CHECK_THROWS_AS(rebuildLevelSet(stock, {3, FamilySet::all(), "", std::array<int, 3>{-1, 0, 0}}), Error);
}

TEST_CASE("rebuild: with one or two families the values do not depend on the index offset", "[surface]") {
    // The walls across a missing axis come from neighbouring dexels (no crossing marks them);
    // beyond the lattice along a kept axis only the band is marked. Offset 0 against random ones
    // (fixed seed): every point's value the same, in and around the lattice.
    std::mt19937 rng(34);
    std::uniform_int_distribution<int> phase(0, 7);
    for (const char* kept : {"z", "xz", "y"}) {
        const FamilySet families = FamilySet::parse(kept);
        TriDexelStock stock = TriDexelStock::fromBox(kStockBox, kH, families);
        testing::carve(stock, testing::boxCutter({kC + Vec3(-9.3, -7.1, 4.2), kC + Vec3(8.8, 6.4, 20.0)}));
        testing::carve(stock, testing::sphere(kC + Vec3(4.0, -3.0, -5.0), 6.0));
        const std::array<int, 3> offset{phase(rng), phase(rng), phase(rng)};
        const LevelSet a = rebuildLevelSet(stock, {3, families, "", std::array<int, 3>{0, 0, 0}});
        const LevelSet b = rebuildLevelSet(stock, {3, families, "", offset});
        INFO("families " << kept << ", offset " << offset[0] << ", " << offset[1] << ", " << offset[2]);
        CHECK(a.activeVoxelCount() == b.activeVoxelCount());
        CHECK(a.activeVoxelCount() > 10000);
        const Lattice& lat = stock.lattice();
        std::size_t differ = 0;
        for (int i = -5; i < lat.n[0] + 5; ++i)
            for (int j = -5; j < lat.n[1] + 5; ++j)
                for (int k = -5; k < lat.n[2] + 5; ++k) differ += a.voxelValue(i, j, k) != b.voxelValue(i, j, k);
        CHECK(differ == 0);
    }
}

TEST_CASE("rebuild: the chosen offset puts each face of a box into one layer of leaves", "[surface]") {
    // A 64^3 lattice: each face's band is six points deep, [-3, 2] and [61, 66]. Offset 0 splits
    // both between two layers of leaves; 3 and 5 put each in one, visiting two layers of blocks
    // (4 puts the search reach of the low face into three).
    const TriDexelStock stock = TriDexelStock::fromBox(kStockBox, kH);
    checkAgainstBruteForce(stock, std::array<int, 3>{3, 3, 3});
    const std::size_t one = rebuildLevelSet(stock, {3, FamilySet::all(), "", std::array<int, 3>{3, 3, 3}}).leafCount();
    const std::size_t two = rebuildLevelSet(stock, {3, FamilySet::all(), "", std::array<int, 3>{0, 0, 0}}).leafCount();
    const LevelSet chosen = rebuildLevelSet(stock);
    INFO("leaves: one layer " << one << ", two layers " << two << ", chosen " << chosen.leafCount());
    CHECK(chosen.leafCount() == one);
    // Measured 438 against 680: the faces halve, the edges and corners (a large share of a box
    // of 8^3 leaves) less.
    CHECK(double(one) < 0.7 * double(two));
    // The values are the lattice's, whatever the offset (as in the grid convention's case).
    CHECK(chosen.voxelValue(0, 30, 30) == Approx(-0.5 * kH));
    CHECK(chosen.voxelValue(-1, 30, 30) == Approx(0.5 * kH));
    CHECK(chosen.valueAt(stock.lattice().point(10, 0, 30)) == Approx(-0.5 * kH));
}

TEST_CASE("rebuild: crossings exactly on lattice points, by brute force", "[surface]") {
    // A segment end on a lattice point: the point is in material at the segment's start and out
    // at its end (material is [lo, hi)), and its distance is the floor kMinDistance. Boxes of
    // random sizes cut from every family alike, their faces on lattice coordinates (i + 1/2) h,
    // exact in float.
    TriDexelStock stock = TriDexelStock::fromBox(kStockBox, kH);
    const Lattice& lat = stock.lattice();
    std::mt19937 rng(12);
    for (int box = 0; box < 6; ++box) {
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            std::uniform_int_distribution<int> at(2, lat.n[a] - 12), size(1, 9);
            lo[a] = at(rng);
            hi[a] = lo[a] + size(rng);
        }
        for (int a = 0; a < 3; ++a) {
            const int b = (a + 1) % 3, c = (a + 2) % 3;
            DexelFamily& fam = stock.family(axisFromIndex(a));
            for (int ic = lo[c]; ic <= hi[c]; ++ic)
                for (int ib = lo[b]; ib <= hi[b]; ++ib)
                    fam.subtract(ib, ic, float((lo[a] + 0.5) * kH), float((hi[a] + 0.5) * kH));
        }
    }
    const auto [active, compared] = checkAgainstBruteForce(stock);
    CHECK(active > 5000);
    CHECK(compared > 300000);
}

TEST_CASE("rebuild: a box meshes to its exact volume", "[surface]") {
    const TriDexelStock stock = TriDexelStock::fromBox(kStockBox, kH);
    const Mesh mesh = meshLevelSet(rebuildLevelSet(stock));
    const MeshCheck check = checkMesh(mesh);
    CHECK(check.ok());
    CHECK(check.signedVolume == Approx(kStockBox.volume()).epsilon(0.005));
}

TEST_CASE("surface: box minus sphere", "[surface]") {
    checkPart({testing::sphere(kC + Vec3(0.0, 0.0, 12.0), 10.0)});
}

TEST_CASE("surface: box minus a tilted cylinder", "[surface]") {
    checkPart({testing::cylinder(kC, Vec3(1.0, 0.5, 2.0), 6.0)});
}

TEST_CASE("surface: box minus a torus", "[surface]") {
    checkPart({testing::torus(kC + Vec3(0.0, 0.0, 11.0), Vec3(0.2, -0.1, 1.0), 9.0, 4.0)});
}

TEST_CASE("surface: pocket with vertical walls", "[surface]") {
    checkPart({testing::boxCutter({kC + Vec3(-7.7, -9.8, 0.3), kC + Vec3(7.7, 9.8, 20.0)})});
}
