// The cutting loop against hand-computed volumes: a rapid and a shank in material, and the
// message of a move whose tool is missing. (cut_test.cpp covers threads, families and culling.)
#include <catch2/catch.hpp>

#include "dexelmill/stock/cut.h"
#include "dexelmill/tool/builders.h"

using namespace dexelmill;

TEST_CASE("a rapid through material and a shank in material are reported", "[stock][cut]") {
    ToolTable table;
    table.emplace(1, flatEndMill(6, {10, 40}));  // 10 mm of flutes on 40 mm of stick-out
    ToolPath p;
    p.files = {"crash.ngc"};
    // A feed slot 5 mm deep, then a rapid 3 mm deep, then a feed 15 mm deep (the shank meets
    // the 5 mm above the flutes).
    p.moves.push_back({Vec3(-5, 10, 15), Vec3(45, 10, 15), Vec3(0, 0, 1), 1, false, {0, 10}, {}, {}});
    p.moves.push_back({Vec3(-5, 20, 17), Vec3(45, 20, 17), Vec3(0, 0, 1), 1, true, {0, 11}, {}, {}});
    p.moves.push_back({Vec3(-5, 30, 5), Vec3(45, 30, 5), Vec3(0, 0, 1), 1, false, {0, 12}, {}, {}});
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
    p.moves.push_back({Vec3(0.0), Vec3(1, 0, 0), Vec3(0, 0, 1), 9, false, {0, 4}, {}, {}});
    TriDexelStock s = TriDexelStock::fromBox(Box{Vec3(0.0), Vec3(10.0)}, 1.0);
    CHECK_THROWS_WITH(cutStock(s, p, ToolTable{}), Catch::Matchers::Contains("prog.ngc:4") &&
                                                       Catch::Matchers::Contains("T9"));
}
