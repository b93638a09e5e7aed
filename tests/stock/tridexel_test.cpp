// The tri-dexel stock: lattice convention, interval algebra against a boolean reference model,
// volumes per family, memory per dexel.
#include <catch2/catch.hpp>

#include <random>

#include "dexelmill/error.h"
#include "dexelmill/stock/tridexel.h"

using namespace dexelmill;

TEST_CASE("lattice points are cell centres from the box minimum", "[stock]") {
    const Lattice l = Lattice::fromBox(Box{Vec3(-10, 0, 5), Vec3(10, 3, 6)}, 0.5);
    CHECK(l.n == std::array<int, 3>{40, 6, 2});
    CHECK(l.point(0, 0, 0) == Vec3(-9.75, 0.25, 5.25));
    CHECK(l.coord(Axis::X, 39) == Approx(9.75));
    // A size that is not a whole number of cells gets a last cell hanging over the box.
    CHECK(Lattice::fromBox(Box{Vec3(0.0), Vec3(1.1, 1, 1)}, 0.5).n[0] == 3);
    // A size that is a whole number up to rounding does not get an extra cell.
    CHECK(Lattice::fromBox(Box{Vec3(0.0), Vec3(0.3, 1, 1)}, 0.1).n[0] == 3);
    const auto r = l.indexRange(Axis::X, -9.8, -9.3);
    CHECK(r[0] == 0);
    CHECK(r[1] == 0);
    const auto none = l.indexRange(Axis::X, -9.7, -9.3);
    CHECK(none[0] > none[1]);
    CHECK_THROWS_AS(Lattice::fromBox(Box{Vec3(0.0), Vec3(1.0)}, 0.0), Error);
    CHECK_THROWS_AS(Lattice::fromBox(Box{Vec3(0.0), Vec3(1, 0, 1)}, 0.1), Error);
    CHECK_THROWS_AS(Lattice::fromBox(Box{Vec3(0.0), Vec3(1e9, 1, 1)}, 1e-3), Error);
}

TEST_CASE("family sets parse and print", "[stock]") {
    CHECK(FamilySet::parse("xyz").mask == 7);
    CHECK(FamilySet::parse("Z").mask == 4);
    CHECK(FamilySet::parse("zx").str() == "xz");
    CHECK_THROWS_AS(FamilySet::parse("xw"), Error);
    CHECK_THROWS_AS(FamilySet::parse("xx"), Error);
    CHECK_THROWS_AS(FamilySet::parse(""), Error);
}

TEST_CASE("dexel subtraction agrees with a boolean reference model", "[stock]") {
    // The reference: a fine boolean array along one dexel, 1 cell per 1/64 mm, with every
    // random endpoint on a cell boundary so both models are exact. It also records the normal of
    // every segment end: the box's faces at first, then the normal of the cut that made the end.
    // A cut from a to b makes an end at a when it splits material there (cells a - 1 and a both
    // in material before it), and one at b likewise; every other end keeps its normal.
    constexpr int kCells = 64 * 40;
    std::mt19937_64 rng(2024);
    std::uniform_int_distribution<int> cell(0, kCells);
    const Box box{Vec3(0.0), Vec3(40.0, 16.0 * 3, 16.0 * 2)};
    TriDexelStock stock = TriDexelStock::fromBox(box, 1.0, FamilySet::only(Axis::X));
    DexelFamily& fam = stock.family(Axis::X);
    const std::size_t dexels = std::size_t(fam.nb() * fam.nc());
    std::vector<std::vector<bool>> ref(dexels, std::vector<bool>(kCells, true));
    // endLo[k]: the normal of a segment starting at cell k; endHi[k]: of one ending after cell k.
    std::vector<std::vector<PackedNormal>> endLo(dexels, std::vector<PackedNormal>(kCells));
    std::vector<std::vector<PackedNormal>> endHi(dexels, std::vector<PackedNormal>(kCells));
    for (std::size_t d = 0; d < dexels; ++d) {
        endLo[d][0] = PackedNormal::pack(Vec3(-1, 0, 0));
        endHi[d][kCells - 1] = PackedNormal::pack(Vec3(1, 0, 0));
    }
    std::normal_distribution<double> gauss;
    for (int op = 0; op < 20000; ++op) {
        const int ib = int(rng() % fam.nb()), ic = int(rng() % fam.nc());
        int a = cell(rng), b = cell(rng);
        if (a > b) std::swap(a, b);
        if (op % 7 == 0) b = std::min(kCells, a + 1 + int(rng() % 3));  // short cuts split dexels
        const std::size_t d = std::size_t(ib + fam.nb() * ic);
        auto& r = ref[d];
        const PackedNormal atLo = PackedNormal::pack(Vec3(gauss(rng), gauss(rng), gauss(rng)), op % 5 == 0);
        const PackedNormal atHi = PackedNormal::pack(Vec3(gauss(rng), gauss(rng), gauss(rng)));
        if (a > 0 && a < kCells && r[a - 1] && r[a]) endHi[d][a - 1] = atLo;
        if (b > 0 && b < kCells && r[b - 1] && r[b]) endLo[d][b] = atHi;
        int removedCells = 0;
        for (int k = a; k < b; ++k) {
            removedCells += r[k];
            r[k] = false;
        }
        const double removed = fam.subtract(ib, ic, float(a / 64.0), float(b / 64.0), atLo, atHi);
        REQUIRE(removed == Approx(removedCells / 64.0).margin(1e-9));
    }
    for (int ic = 0; ic < fam.nc(); ++ic) {
        for (int ib = 0; ib < fam.nb(); ++ib) {
            const std::size_t d = std::size_t(ib + fam.nb() * ic);
            const auto& r = ref[d];
            std::vector<Segment> want;
            for (int k = 0; k < kCells; ++k) {
                if (!r[k]) continue;
                if (!want.empty() && want.back().hi == float(k / 64.0)) {
                    want.back().hi = float((k + 1) / 64.0);
                    want.back().nhi = endHi[d][k];
                } else {
                    want.push_back({float(k / 64.0), float((k + 1) / 64.0), endLo[d][k], endHi[d][k]});
                }
            }
            const SegmentSpan got = fam.segments(ib, ic);
            REQUIRE(got.size == want.size());
            for (std::size_t s = 0; s < want.size(); ++s) {
                CHECK(got[s].lo == want[s].lo);
                CHECK(got[s].hi == want[s].hi);
                CHECK(got[s].nlo == want[s].nlo);
                CHECK(got[s].nhi == want[s].nhi);
            }
        }
    }
}

TEST_CASE("a box stock: one segment per dexel, equal volumes, inside everywhere", "[stock]") {
    const Box box{Vec3(1, 2, 3), Vec3(11.3, 7, 9)};
    const TriDexelStock s = TriDexelStock::fromBox(box, 0.5);
    CHECK(s.lattice().n == std::array<int, 3>{21, 10, 12});
    // Every family measures the box: 10.3 mm is 20.6 cells, and the last x line (at 10.25 of
    // 10.3 mm) stands for the last 0.6 of a cell, not a whole one. The dexels' lengths are
    // floats: 10.3 mm is stored within 2^-24 of itself.
    for (const Axis a : {Axis::X, Axis::Y, Axis::Z}) CHECK(s.volume(a) == Approx(10.3 * 5.0 * 6.0).epsilon(0x1p-23));
    CHECK(s.inside(Axis::X, 20, 9, 11));
    CHECK(s.inside(Axis::Z, 0, 0, 0));
    CHECK(s.dexelCount() == std::size_t(10 * 12 + 12 * 21 + 21 * 10));
    const Line l = s.dexelLine(Axis::Y, 3, 4);  // along y through z index 3, x index 4
    CHECK(l.origin == Vec3(1 + 4.5 * 0.5, 2, 3 + 3.5 * 0.5));
    CHECK(l.dir == Vec3(0, 1, 0));
}

TEST_CASE("memory: one-segment dexels cost at most 24 bytes, empty tiles almost nothing", "[stock]") {
    // A segment is two float ends and two packed normals (16 bytes); a dexel adds its offset (4)
    // and count (2), and a share of the tile header.
    TriDexelStock s = TriDexelStock::fromBox(Box{Vec3(0.0), Vec3(256.0)}, 1.0);
    const double perDexel = double(s.memoryBytes()) / double(s.dexelCount());
    INFO("bytes per one-segment dexel: " << perDexel);
    CHECK(perDexel <= 24.0);
    // Empty every z dexel: the tiles release their arrays.
    DexelFamily& z = s.family(Axis::Z);
    for (int ic = 0; ic < z.nc(); ++ic)
        for (int ib = 0; ib < z.nb(); ++ib) z.subtract(ib, ic, -1.0f, 300.0f);
    CHECK(z.materialLength() == 0);
    CHECK(double(z.memoryBytes()) / (256.0 * 256.0) < 1.0);
    CHECK_THROWS_AS(TriDexelStock(s.lattice(), FamilySet::only(Axis::X)).family(Axis::Y), Error);
}

TEST_CASE("a box whose size is not a whole number of cells: lines past it hold nothing", "[stock]") {
    // 10.3 mm at h = 1 gives 11 lattice lines; the last, at 10.5, lies outside the box.
    const TriDexelStock s = TriDexelStock::fromBox(Box{Vec3(0.0), Vec3(10.3, 4, 4)}, 1.0);
    REQUIRE(s.lattice().n[0] == 11);
    CHECK(s.family(Axis::Z).segments(10, 0).empty());  // z dexel at x = 10.5
    CHECK_FALSE(s.family(Axis::Z).segments(9, 0).empty());
    CHECK(s.family(Axis::Y).segments(0, 10).empty());  // y dexels run through (z, x)
    for (int k = 0; k < 4; ++k)
        for (int j = 0; j < 4; ++j) {
            CHECK(s.inside(Axis::X, 10, j, k) == s.inside(Axis::Z, 10, j, k));
            CHECK(s.inside(Axis::Y, 10, j, k) == s.inside(Axis::Z, 10, j, k));
        }
    CHECK(s.volume(Axis::X) == Approx(s.volume(Axis::Z)).epsilon(0.1));
}
