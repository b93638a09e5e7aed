// The cutting loop: determinism across thread counts, agreement of the three families, and the
// collisions it reports.
#include <catch2/catch.hpp>

#include <cstring>
#include <random>

#include "dexelmill/stock/cut.h"
#include "dexelmill/tool/builders.h"

using namespace dexelmill;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// A random program of `n` moves over a 40 x 30 x 20 block: mixed tools, tilted axes, plunges,
/// ramps and horizontal moves, all starting above the block.
ToolPath randomProgram(int n, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> ux(-5, 45), uy(-5, 35), uz(8, 24), u01(0, 1);
    ToolPath p;
    p.files = {"random"};
    Vec3 at(20, 15, 30);
    for (int i = 0; i < n; ++i) {
        Move m;
        m.start = at;
        const double kind = u01(rng);
        if (kind < 0.15) m.end = at + Vec3(0, 0, uz(rng) - at.z);          // plunge / retract
        else if (kind < 0.4) m.end = Vec3(ux(rng), uy(rng), at.z);          // horizontal
        else m.end = Vec3(ux(rng), uy(rng), uz(rng));                        // general
        if (i % 7 == 3) {
            const double t = u01(rng) * 35 * kPi / 180, a = u01(rng) * 2 * kPi;
            m.axis = Vec3(std::sin(t) * std::cos(a), std::sin(t) * std::sin(a), std::cos(t));
        }
        m.tool = 1 + i % 4;
        m.source = {0, i + 1};
        p.moves.push_back(m);
        at = m.end;
    }
    return p;
}

ToolTable tools() {
    ToolTable t;
    t.emplace(1, ballEndMill(6, {30, 40}));
    t.emplace(2, flatEndMill(5, {30, 40}));
    t.emplace(3, bullNoseEndMill(8, 2, {30, 40}));
    t.emplace(4, chamferMill(1, 30 * kPi / 180, 8, {30, 40}));
    return t;
}

bool sameSegments(const TriDexelStock& a, const TriDexelStock& b) {
    for (int f = 0; f < 3; ++f) {
        const Axis ax = axisFromIndex(f);
        const DexelFamily& fa = a.family(ax);
        const DexelFamily& fb = b.family(ax);
        for (int ic = 0; ic < fa.nc(); ++ic)
            for (int ib = 0; ib < fa.nb(); ++ib) {
                const SegmentSpan sa = fa.segments(ib, ic), sb = fb.segments(ib, ic);
                if (sa.size != sb.size) return false;
                if (sa.size && std::memcmp(sa.data, sb.data, sa.size * sizeof(Segment)) != 0) return false;
            }
    }
    return true;
}

}  // namespace

TEST_CASE("cutting gives the same result bit for bit on 1 and 2 threads", "[stock][cut]") {
    const ToolPath path = randomProgram(300, 42);
    const ToolTable table = tools();
    const Box box{Vec3(0.0), Vec3(40, 30, 20)};
    TriDexelStock one = TriDexelStock::fromBox(box, 0.4);
    TriDexelStock two = TriDexelStock::fromBox(box, 0.4);
    CutOptions o1, o2;
    o1.threads = 1;
    o2.threads = 2;
    const CutResult r1 = cutStock(one, path, table, o1);
    const CutResult r2 = cutStock(two, path, table, o2);
    CHECK(sameSegments(one, two));
    REQUIRE(r1.moves.size() == r2.moves.size());
    bool sameStats = true;
    for (std::size_t i = 0; i < r1.moves.size(); ++i) {
        sameStats = sameStats && r1.moves[i].removed == r2.moves[i].removed &&
                    r1.moves[i].visited == r2.moves[i].visited && r1.moves[i].changed == r2.moves[i].changed;
    }
    CHECK(sameStats);
    CHECK(r1.removedVolume == r2.removedVolume);
    CHECK(r1.removedVolume > 100.0);
}

TEST_CASE("after a random program the three families agree", "[stock][cut]") {
    const ToolPath path = randomProgram(250, 7);
    const Box box{Vec3(0.0), Vec3(40, 30, 20)};
    for (double h : {0.5, 0.25}) {
        TriDexelStock s = TriDexelStock::fromBox(box, h);
        cutStock(s, path, tools());
        const double vx = s.volume(Axis::X), vy = s.volume(Axis::Y), vz = s.volume(Axis::Z);
        // Each family integrates the same solid with a midpoint rule across its rays: the
        // difference is O(h^2) times the surface's curvature; with these tools (radii >= 2.5 mm)
        // and a part of ~9000 mm^2 surface, area * h^2 / 4 bounds it generously.
        const double bound = 9000 * h * h / 4;
        INFO("h " << h << ": x " << vx << ", y " << vy << ", z " << vz);
        CHECK(std::abs(vx - vz) < bound);
        CHECK(std::abs(vy - vz) < bound);
        // Every lattice point: the three dexels through it agree on inside or outside.
        const Lattice& l = s.lattice();
        std::size_t disagree = 0, points = 0;
        for (int k = 0; k < l.n[2]; ++k)
            for (int j = 0; j < l.n[1]; ++j)
                for (int i = 0; i < l.n[0]; ++i) {
                    const bool x = s.inside(Axis::X, i, j, k);
                    disagree += (x != s.inside(Axis::Y, i, j, k)) + (x != s.inside(Axis::Z, i, j, k));
                    ++points;
                }
        CHECK(disagree == 0);
        CHECK(points == std::size_t(l.n[0]) * l.n[1] * l.n[2]);
    }
}

TEST_CASE("a rapid through material and a shank in material are reported", "[stock][cut]") {
    ToolTable table;
    table.emplace(1, flatEndMill(6, {10, 40}));  // 10 mm of flutes on 40 mm of stick-out
    ToolPath p;
    p.files = {"crash.ngc"};
    // A feed slot 5 mm deep, then a rapid 3 mm deep, then a feed 15 mm deep (the shank meets
    // the 5 mm above the flutes).
    p.moves.push_back({Vec3(-5, 10, 15), Vec3(45, 10, 15), Vec3(0, 0, 1), 1, false, {0, 10}});
    p.moves.push_back({Vec3(-5, 20, 17), Vec3(45, 20, 17), Vec3(0, 0, 1), 1, true, {0, 11}});
    p.moves.push_back({Vec3(-5, 30, 5), Vec3(45, 30, 5), Vec3(0, 0, 1), 1, false, {0, 12}});
    TriDexelStock s = TriDexelStock::fromBox(Box{Vec3(0.0), Vec3(40, 40, 20)}, 0.25);
    const CutResult r = cutStock(s, p, table);
    REQUIRE(r.collisions.size() == 2);
    CHECK(r.collisions[0].kind == CollisionKind::Rapid);
    CHECK(r.collisions[0].move == 1);
    CHECK(r.collisions[0].source.line == 11);
    // 40 mm long, 6 wide, 3 deep (the slot's round ends are outside the block).
    CHECK(r.collisions[0].volume == Approx(40 * 6 * 3).epsilon(0.02));
    CHECK(r.collisions[1].kind == CollisionKind::Shank);
    CHECK(r.collisions[1].move == 2);
    CHECK(r.collisions[1].volume == Approx(40 * 6 * 5).epsilon(0.02));
    // The feed slot alone: 40 x 6 x 5.
    CHECK(r.moves[0].removed == Approx(40 * 6 * 5).epsilon(0.02));
    CHECK(r.moves[0].changed > 0);
    CHECK(r.moves[0].visited >= r.moves[0].changed);
}

TEST_CASE("a move naming an undefined tool is an error with its line", "[stock][cut][errors]") {
    ToolPath p;
    p.files = {"prog.ngc"};
    p.moves.push_back({Vec3(0.0), Vec3(1, 0, 0), Vec3(0, 0, 1), 9, false, {0, 4}});
    TriDexelStock s = TriDexelStock::fromBox(Box{Vec3(0.0), Vec3(10.0)}, 1.0);
    CHECK_THROWS_WITH(cutStock(s, p, ToolTable{}), Catch::Matchers::Contains("prog.ngc:4") &&
                                                       Catch::Matchers::Contains("T9"));
}
