#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
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
    const LevelSet ls = rebuildLevelSet(stock, {3, FamilySet::all(), "test"});
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

/// The estimate of method.md section 7 worked out per voxel of the stock's lattice (and 4 points
/// around it) with no block marks, binary searches or early outs: each family's dexel through the
/// voxel scanned end to end. Returns the active voxels the oracle finds (the grid must hold the
/// same number) and how many voxels it compared.
std::pair<std::size_t, std::size_t> checkAgainstBruteForce(const TriDexelStock& stock) {
    const int halfWidth = 3;
    const LevelSet ls = rebuildLevelSet(stock, {halfWidth, FamilySet::all(), "test"});
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
                ++compared;
                INFO("voxel (" << i << ", " << j << ", " << k << ")");
                REQUIRE(std::abs(ls.voxelValue(i, j, k) - expected) <= kFloatSum * std::abs(expected));
            }
    CHECK(active == ls.activeVoxelCount());
    return {active, compared};
}

}  // namespace

TEST_CASE("rebuild: grid convention, class, name and metadata", "[surface]") {
    const TriDexelStock stock = TriDexelStock::fromBox(kStockBox, kH);
    const LevelSet ls = rebuildLevelSet(stock, {3, FamilySet::all(), "box"});
    CHECK(ls.voxelSize() == Approx(kH));
    CHECK(ls.halfWidth() == Approx(3.0));
    CHECK(ls.source() == "box");
    REQUIRE(ls.lattice().has_value());
    CHECK(ls.lattice()->n == stock.lattice().n);
    // Voxel (i,j,k) is lattice point (i,j,k): point 0 lies h/2 inside the box face, point -1
    // h/2 outside, and both are exact distances to the plane.
    CHECK(ls.voxelValue(0, 30, 30) == Approx(-0.5 * kH));
    CHECK(ls.voxelValue(-1, 30, 30) == Approx(0.5 * kH));
    CHECK(ls.voxelValue(2, 30, 30) == Approx(-2.5 * kH));
    CHECK(ls.voxelValue(30, 30, 30) == Approx(-3.0 * kH));  // interior background
    CHECK(ls.voxelValue(-10, 30, 30) == Approx(3.0 * kH));   // exterior background
    // Near a box corner the three axis distances combine: h/2 from each face.
    CHECK(ls.voxelValue(0, 0, 0) == Approx(-0.5 * kH / std::sqrt(3.0)));
    CHECK(ls.valueAt(stock.lattice().point(10, 0, 30)) == Approx(-0.5 * kH));
    CHECK_THROWS_AS(rebuildLevelSet(stock, {2, FamilySet::all(), ""}), Error);
}

TEST_CASE("rebuild: every voxel holds the axis-distance estimate, by brute force", "[surface]") {
    TriDexelStock stock = TriDexelStock::fromBox(kStockBox, kH);
    testing::carve(stock, testing::sphere(kC + Vec3(0.0, 0.0, 12.0), 10.0));
    testing::carve(stock, testing::torus(kC + Vec3(0.0, 0.0, -4.0), Vec3(0.2, -0.1, 1.0), 9.0, 4.0));
    const auto [active, compared] = checkAgainstBruteForce(stock);
    CHECK(active > 10000);
    CHECK(compared > 300000);
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
