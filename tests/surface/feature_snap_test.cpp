#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "dexelmill/surface/feature_snap.h"
#include "dexelmill/surface/levelset.h"
#include "support/analytic_parts.h"

using namespace dexelmill;

namespace {

constexpr double kH = 0.5;
const Box kBox{Vec3(0.0), Vec3(32.0, 32.0, 24.0)};
// A pocket with vertical walls, open at the top; its walls and floor fall between lattice
// planes at different fractions of h.
const Box kPocket{Vec3(8.3, 6.2, 12.35), Vec3(23.7, 25.85, 40.0)};

/// Distance from p to the axis-aligned rectangle at coordinate `at` on axis a, spanning
/// [lo, hi] on the two other axes (lo/hi given as full vectors; their a-components ignored).
double rectDistance(const Vec3& p, int a, double at, const Vec3& lo, const Vec3& hi) {
    double d2 = (p[a] - at) * (p[a] - at);
    for (int k = 0; k < 3; ++k) {
        if (k == a) continue;
        const double out = std::max({lo[k] - p[k], 0.0, p[k] - hi[k]});
        d2 += out * out;
    }
    return std::sqrt(d2);
}

/// Exact distance from p to the surface of the box minus the pocket.
double pocketPartDistance(const Vec3& p) {
    const Vec3 top(kBox.hi.x, kBox.hi.y, kBox.hi.z);
    const Vec3 wallTop(kPocket.hi.x, kPocket.hi.y, kBox.hi.z);
    double d = std::numeric_limits<double>::infinity();
    // The box's four sides and bottom.
    for (int a = 0; a < 3; ++a) {
        d = std::min(d, rectDistance(p, a, kBox.lo[a], kBox.lo, kBox.hi));
        if (a != 2) d = std::min(d, rectDistance(p, a, kBox.hi[a], kBox.lo, kBox.hi));
    }
    // The pocket's floor and walls.
    d = std::min(d, rectDistance(p, 2, kPocket.lo.z, kPocket.lo, wallTop));
    for (int a = 0; a < 2; ++a) {
        d = std::min(d, rectDistance(p, a, kPocket.lo[a], kPocket.lo, wallTop));
        d = std::min(d, rectDistance(p, a, kPocket.hi[a], kPocket.lo, wallTop));
    }
    // The top face, less the pocket's opening.
    const bool inOpening = p.x > kPocket.lo.x && p.x < kPocket.hi.x && p.y > kPocket.lo.y &&
                           p.y < kPocket.hi.y;
    if (inOpening) {
        const double rim = std::min({p.x - kPocket.lo.x, kPocket.hi.x - p.x, p.y - kPocket.lo.y,
                                     kPocket.hi.y - p.y});
        d = std::min(d, std::hypot(p.z - top.z, rim));
    } else {
        d = std::min(d, rectDistance(p, 2, top.z, kBox.lo, top));
    }
    return d;
}

struct EdgeError {
    double max = 0.0, rms = 0.0;
    std::size_t count = 0;
};

/// Error of the vertices within 1.5 h of two pocket planes (its eight edges, rim and floor, and
/// four vertical corners).
EdgeError pocketEdgeError(const Mesh& mesh) {
    EdgeError e;
    double sum2 = 0.0;
    for (const Vec3& v : mesh.vertices) {
        int near = 0;
        for (int a = 0; a < 3; ++a) {
            near += std::abs(v[a] - kPocket.lo[a]) < 1.5 * kH;
            near += a < 2 && std::abs(v[a] - kPocket.hi[a]) < 1.5 * kH;
        }
        near += std::abs(v.z - kBox.hi.z) < 1.5 * kH;
        const bool inPocketColumn = v.x > kPocket.lo.x - 1.5 * kH && v.x < kPocket.hi.x + 1.5 * kH &&
                                    v.y > kPocket.lo.y - 1.5 * kH && v.y < kPocket.hi.y + 1.5 * kH &&
                                    v.z > kPocket.lo.z - 1.5 * kH;
        if (near < 2 || !inPocketColumn) continue;
        const double d = pocketPartDistance(v);
        e.max = std::max(e.max, d);
        sum2 += d * d;
        ++e.count;
    }
    e.rms = e.count ? std::sqrt(sum2 / double(e.count)) : 0.0;
    return e;
}

}  // namespace

TEST_CASE("feature snapping sharpens 90 degree pocket edges", "[surface]") {
    TriDexelStock stock = TriDexelStock::fromBox(kBox, kH);
    testing::carve(stock, testing::boxCutter(kPocket));
    const Mesh plain = meshLevelSet(rebuildLevelSet(stock));
    Mesh snapped = plain;
    const SnapStats stats = snapFeatures(snapped, stock);
    CHECK(stats.edgeVertices > 0);
    CHECK(stats.cornerVertices > 0);

    const MeshCheck check = checkMesh(snapped);
    CHECK(check.closedManifold());
    CHECK(check.degenerateTriangles == 0);
    const double v = stock.volume(Axis::Z);
    const double before = std::abs(meshVolume(plain) - v) / v;
    const double after = std::abs(check.signedVolume - v) / v;
    CHECK(after <= before);

    const EdgeError e0 = pocketEdgeError(plain), e1 = pocketEdgeError(snapped);
    INFO("pocket edges, " << e0.count << " vertices: plain max " << e0.max / kH << " h rms "
                          << e0.rms / kH << " h; snapped max " << e1.max / kH << " h rms "
                          << e1.rms / kH << " h; volume error " << before << " -> " << after);
    REQUIRE(e0.count == e1.count);
    CHECK(e1.max < 0.5 * e0.max);
    CHECK(e1.rms < 0.5 * e0.rms);
    CHECK(e1.max <= 0.1 * kH);
}

TEST_CASE("feature snapping keeps smooth surfaces accurate", "[surface]") {
    const Box box{Vec3(0.0), Vec3(32.0)};
    TriDexelStock stock = TriDexelStock::fromBox(box, kH);
    const testing::Cutter ball = testing::sphere(Vec3(16.0, 16.0, 28.0), 10.0);
    testing::carve(stock, ball);
    Mesh mesh = meshLevelSet(rebuildLevelSet(stock));
    snapFeatures(mesh, stock);
    CHECK(checkMesh(mesh).closedManifold());
    const testing::PartSurfaces part(box, {ball});
    double worst = 0.0, sum2 = 0.0;
    std::size_t n = 0;
    for (const Vec3& v : mesh.vertices) {
        const auto [d, nearFeature] = part.measure(v, 2.0 * kH);
        if (nearFeature) continue;
        worst = std::max(worst, d);
        sum2 += d * d;
        ++n;
    }
    CHECK(worst <= 0.1 * kH);
    CHECK(std::sqrt(sum2 / double(n)) <= 0.02 * kH);
}
