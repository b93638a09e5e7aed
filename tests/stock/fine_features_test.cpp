// Stretches of a dexel that hold no lattice point (finerThanLattice), against an oracle that tests
// every lattice point of every dexel, and on walls and slots whose answer is known.
#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <vector>

#include "dexelmill/stock/fine_features.h"
#include "support/analytic_parts.h"

using namespace dexelmill;

namespace {

/// One stretch as the oracle finds it.
struct Stretch {
    int family;
    double length;
    Vec3 middle;
};

/// Every stretch of `stock` holding no lattice point: material (`gaps` false), strictly inside a
/// segment, or gaps between two segments, ends included. Each dexel's lattice points are all
/// tested, at (i + 1/2) h as floats.
std::vector<Stretch> oracle(const TriDexelStock& stock, bool gaps) {
    std::vector<Stretch> out;
    const Lattice& lat = stock.lattice();
    for (int a = 0; a < 3; ++a) {
        const Axis axis = axisFromIndex(a);
        if (!stock.has(axis)) continue;
        const DexelFamily& fam = stock.family(axis);
        const auto empty = [&](double lo, double hi) {
            for (int i = 0; i < lat.n[std::size_t(a)]; ++i) {
                const float v = float((i + 0.5) * lat.h);
                if (gaps ? (lo <= v && v <= hi) : (lo < v && v < hi)) return false;
            }
            return true;
        };
        for (int ic = 0; ic < fam.nc(); ++ic)
            for (int ib = 0; ib < fam.nb(); ++ib) {
                const SegmentSpan s = fam.segments(ib, ic);
                for (std::size_t k = 0; k < s.size; ++k) {
                    double lo = s[k].lo, hi = s[k].hi;
                    if (gaps) {
                        if (k + 1 == s.size || !(s[k + 1].lo > s[k].hi)) continue;
                        lo = s[k].hi, hi = s[k + 1].lo;
                    }
                    if (empty(lo, hi))
                        out.push_back(
                            {a, hi - lo, stock.dexelLine(axis, ib, ic).at(0.5 * (lo + hi))});
                }
            }
    }
    return out;
}

/// Checks `found` against the oracle's stretches.
void checkAgainst(const FineStretches& found, const std::vector<Stretch>& expected, double h) {
    CHECK(found.count == expected.size());
    double perFamily[3] = {0.0, 0.0, 0.0}, widest = 0.0;
    for (const Stretch& s : expected)
        perFamily[s.family] += s.length, widest = std::max(widest, s.length);
    // Each region's volume is its best family's: at least one family's total, at most all three.
    CHECK(found.volumeMm3 >= h * h * *std::max_element(perFamily, perFamily + 3) * (1.0 - 1e-12));
    CHECK(found.volumeMm3 <= h * h * (perFamily[0] + perFamily[1] + perFamily[2]) * (1.0 + 1e-12));
    CHECK(found.widestMm == widest);
    // The regions kept: most volume first, and all of the stretches when all are kept.
    REQUIRE(found.regionCount >= 1);
    CHECK(found.regions.size() == std::min(found.regionCount, kFineRegionsKept));
    std::size_t inRegions = 0;
    for (std::size_t r = 0; r < found.regions.size(); ++r) {
        inRegions += found.regions[r].stretches;
        if (r > 0) CHECK(found.regions[r - 1].volumeMm3 >= found.regions[r].volumeMm3);
    }
    if (found.regionCount <= kFineRegionsKept) CHECK(inRegions == found.count);
    // Several stretches may be the widest: the one named is one of them.
    CHECK(std::any_of(expected.begin(), expected.end(), [&](const Stretch& s) {
        return s.length == widest && s.middle == found.widestAt;
    }));
}

}  // namespace

TEST_CASE("fine features: random dexels against every lattice point", "[stock][fine]") {
    // Spacing 1 and cut ends on a grid of quarters: the lattice points (i + 1/2) are exact, and
    // many ends fall on one, where material is open and a gap closed.
    const double h = 1.0;
    for (const unsigned seed : {1u, 2u, 3u}) {
        TriDexelStock stock = TriDexelStock::fromBox(Box{Vec3(0.0), Vec3(12.0, 6.0, 5.0)}, h);
        std::mt19937 rng(seed);
        for (int a = 0; a < 3; ++a) {
            DexelFamily& fam = stock.family(axisFromIndex(a));
            std::uniform_int_distribution<int> quarter(0, 4 * stock.lattice().n[std::size_t(a)]);
            std::uniform_int_distribution<int> cuts(0, 4);
            for (int ic = 0; ic < fam.nc(); ++ic)
                for (int ib = 0; ib < fam.nb(); ++ib)
                    for (int c = cuts(rng); c > 0; --c) {
                        const int q0 = quarter(rng), q1 = quarter(rng);
                        fam.subtract(ib, ic, 0.25f * float(std::min(q0, q1)),
                                     0.25f * float(std::max(q0, q1)));
                    }
        }
        const FineFeatures f = finerThanLattice(stock);
        const std::vector<Stretch> material = oracle(stock, false), gaps = oracle(stock, true);
        INFO("seed " << seed << ": " << material.size() << " material and " << gaps.size()
                     << " gap stretches");
        REQUIRE(!material.empty());
        REQUIRE(!gaps.empty());
        checkAgainst(f.material, material, h);
        checkAgainst(f.gaps, gaps, h);
    }
}

TEST_CASE("fine features: a wall and a slot thinner than the spacing", "[stock][fine]") {
    // Spacing 1 on a 32 x 32 x 24 block: lattice planes at x = 15.5 and 16.5. Between y 5.2 and
    // 27.1 and above z 8.3 lie 22 x 16 x-dexels (y and z from 5.5 and 8.5 on).
    const Box block{Vec3(0.0), Vec3(32.0, 32.0, 24.0)};
    const double y0 = 5.2, y1 = 27.1, z0 = 8.3;
    const std::size_t dexels = 22 * 16;
    const auto pocket = [&](double x0, double x1) {
        return testing::boxCutter({Vec3(x0, y0, z0), Vec3(x1, y1, 30.0)});
    };
    const auto features = [&](const std::vector<testing::Cutter>& cuts) {
        TriDexelStock stock = TriDexelStock::fromBox(block, 1.0);
        for (const testing::Cutter& c : cuts) testing::carve(stock, c);
        return finerThanLattice(stock);
    };

    SECTION("a wall 0.7 thick between two lattice planes") {
        const FineFeatures f = features({pocket(4.0, 15.6), pocket(16.3, 28.0)});
        CHECK(f.material.count == dexels);
        CHECK(f.material.widestMm == Approx(0.7).margin(1e-5));
        CHECK(f.material.volumeMm3 == Approx(0.7 * double(dexels)).margin(1e-3));
        CHECK(f.material.widestAt.x == Approx(15.95).margin(1e-5));
        CHECK(f.gaps.count == 0);
        // One region: the wall, its dexels' cells from y 5 to 27 and z 8 to 24.
        REQUIRE(f.material.regionCount == 1);
        const FineRegion& wall = f.material.regions.at(0);
        CHECK(wall.stretches == dexels);
        CHECK(wall.volumeMm3 == Approx(f.material.volumeMm3));
        CHECK(wall.box.lo.x == Approx(15.6).margin(1e-5));
        CHECK(wall.box.hi.x == Approx(16.3).margin(1e-5));
        CHECK(wall.box.lo.y == Approx(5.0));
        CHECK(wall.box.hi.y == Approx(27.0));
        CHECK(wall.box.lo.z == Approx(8.0));
        CHECK(wall.box.hi.z == Approx(24.0));
    }
    SECTION("two walls apart are two regions, the larger first") {
        // 0.7 thick over y 5.2 to 15 (10 x 16 dexels), and 0.3 thick at x 20.6 over y 18 to 27.1
        // (9 x 16), 3 mm further on: more than a region's cells join.
        const auto cut = [&](double x0, double ya, double x1, double yb) {
            return testing::boxCutter({Vec3(x0, ya, z0), Vec3(x1, yb, 30.0)});
        };
        const FineFeatures f = features({cut(4.0, y0, 15.6, 15.0), cut(16.3, y0, 28.0, 15.0),
                                         cut(4.0, 18.0, 20.6, y1), cut(20.9, 18.0, 28.0, y1)});
        CHECK(f.material.count == 160 + 144);
        REQUIRE(f.material.regionCount == 2);
        CHECK(f.material.regions.at(0).volumeMm3 == Approx(0.7 * 160).margin(1e-3));
        CHECK(f.material.regions.at(0).widestAt.x == Approx(15.95).margin(1e-5));
        CHECK(f.material.regions.at(1).volumeMm3 == Approx(0.3 * 144).margin(1e-3));
        CHECK(f.material.regions.at(1).widestAt.x == Approx(20.75).margin(1e-5));
        CHECK(f.material.volumeMm3 == Approx(0.7 * 160 + 0.3 * 144).margin(1e-3));
    }
    SECTION("a wall 0.6 thick holding a lattice plane") {
        const FineFeatures f = features({pocket(4.0, 15.3), pocket(15.9, 28.0)});
        CHECK(f.material.count == 0);
        CHECK(f.gaps.count == 0);
    }
    SECTION("a slot 0.7 wide between two lattice planes") {
        const FineFeatures f = features({pocket(15.6, 16.3)});
        CHECK(f.gaps.count == dexels);
        CHECK(f.gaps.widestMm == Approx(0.7).margin(1e-5));
        CHECK(f.gaps.widestAt.x == Approx(15.95).margin(1e-5));
        CHECK(f.material.count == 0);
    }
    SECTION("a slot 0.7 wide across a lattice plane") {
        const FineFeatures f = features({pocket(15.2, 15.9)});
        CHECK(f.gaps.count == 0);
        CHECK(f.material.count == 0);
    }
    SECTION("a skin 0.3 thick on the block's face, outside its first lattice plane") {
        const FineFeatures f =
            features({testing::boxCutter({Vec3(-1.0, y0, z0), Vec3(31.7, y1, 30.0)})});
        CHECK(f.material.count == dexels);
        CHECK(f.material.widestMm == Approx(0.3).margin(1e-5));
        CHECK(f.material.widestAt.x == Approx(31.85).margin(1e-5));
    }
}

TEST_CASE("fine features: degenerate stocks", "[stock][fine][degenerate]") {
    const Box block{Vec3(0.0), Vec3(8.0, 4.0, 4.0)};
    SECTION("no material at all") {
        const FineFeatures f = finerThanLattice(TriDexelStock(Lattice::fromBox(block, 1.0)));
        CHECK(f.material.count == 0);
        CHECK(f.gaps.count == 0);
        CHECK(f.material.regions.empty());
        CHECK(f.material.volumeMm3 == 0.0);
    }
    SECTION("one family: only its dexels are searched") {
        // An uncut z-only block holds no stretch, and the families it lacks are not asked for. A
        // sliver from x 2.6 to 2.9 (lattice points at 2.5 and 3.5) left on an x-only block's dexel
        // is one.
        CHECK(finerThanLattice(TriDexelStock::fromBox(block, 1.0, FamilySet::only(Axis::Z))).material.count == 0);
        TriDexelStock x = TriDexelStock::fromBox(block, 1.0, FamilySet::only(Axis::X));
        x.family(Axis::X).subtract(1, 1, 0.0f, 2.6f);
        x.family(Axis::X).subtract(1, 1, 2.9f, 8.0f);
        const FineFeatures f = finerThanLattice(x);
        REQUIRE(f.material.count == 1);
        CHECK(f.material.widestMm == Approx(0.3).margin(1e-6));
        CHECK(f.material.widestAt.x == Approx(2.75).margin(1e-6));
        CHECK(f.material.widestAt.y == 1.5);
        CHECK(f.material.widestAt.z == 1.5);
        CHECK(f.material.regionCount == 1);
        CHECK(f.material.volumeMm3 == Approx(0.3).margin(1e-6));
    }
    SECTION("segments that touch leave no gap") {
        TriDexelStock x = TriDexelStock::fromBox(block, 1.0, FamilySet::only(Axis::X));
        const Segment touching[2] = {{0.0f, 2.75f, {}, {}}, {2.75f, 8.0f, {}, {}}};
        x.family(Axis::X).setSegments(0, 0, touching, 2);
        CHECK(finerThanLattice(x).gaps.count == 0);
        CHECK(finerThanLattice(x).material.count == 0);
    }
}
