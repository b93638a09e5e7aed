// The cutting loop against hand-computed volumes: a rapid and a shank in material, and the
// message of a move whose tool is missing; a turning move's shank against a closed-form oracle.
// (cut_test.cpp covers threads, families and culling.)
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

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

namespace {

/// Whether some pose of a pure rotation about the tip (the origin) puts the point (X, y, Z) inside
/// the cylinder of radius r between heights lo >= 0 and hi along the tool axis. The axis turns in
/// the xz-plane from +z towards +x through angles [from, to]. In the tool's frame at angle t the
/// point lies at angle psi = phi - t from the axis (phi: its own angle from +z); it is inside
/// when rho |sin psi| <= sqrt(r^2 - y^2) and lo <= rho cos psi <= hi, that is when
/// b <= |psi| <= a for the angles a and b below, psi taken in [-pi, pi] (the turn's angles
/// reach the point's from either side). Closed form: no sweep code is shared.
bool inTurningCylinder(double X, double y, double Z, double r, double lo, double hi, double from, double to) {
    if (std::abs(y) >= r) return false;
    const double c = std::sqrt(r * r - y * y), rho = std::hypot(X, Z);
    if (rho <= 0.0 || lo > rho) return false;
    const double halfPi = std::acos(0.0);
    const double a = std::min(c >= rho ? halfPi : std::asin(c / rho), std::acos(lo / rho));
    const double b = hi >= rho ? 0.0 : std::acos(hi / rho);
    if (b > a) return false;
    const double phi = std::atan2(X, Z);
    const double twoPi = 4.0 * halfPi;
    for (const double wrap : {-twoPi, 0.0, twoPi}) {
        const auto meets = [&](double l, double h) {
            return std::max(l, phi - to + wrap) <= std::min(h, phi - from + wrap);
        };
        if (meets(b, a) || meets(-a, -b)) return true;
    }
    return false;
}

/// The tip both turning tests turn the tool about.
const Vec3 kTurnTip(20.0, 20.0, 12.0);

/// A flat D6 with 10 mm of flutes on 40 mm, as tool 1.
ToolTable flutedD6() {
    ToolTable table;
    table.emplace(1, flatEndMill(6, {10, 40}));
    return table;
}

/// One move of tool 1 at `line` of `file`, turning `turn` radians about kTurnTip from +z towards +x.
ToolPath turnAboutTip(double turn, const char* file, int line) {
    ToolPath p;
    p.files = {file};
    Move m{kTurnTip, kTurnTip, Vec3(std::sin(turn), 0.0, std::cos(turn)), 1, false, {0, line}, {}, {}};
    m.startAxis = Vec3(0.0, 0.0, 1.0);
    p.moves.push_back(m);
    return p;
}

}  // namespace

TEST_CASE("a turning move whose shank sweeps through material is reported with what it meets",
          "[stock][cut][turning]") {
    // A flat D6, 10 mm of flutes on 40 mm, turns 20 degrees about its tip at (20, 20, 12), from
    // +z towards +x, in a block 30 mm high: the flutes sweep a fan from heights 12 to 22, the
    // shank one above them. What the shank meets is the block inside the shank's fan and outside
    // the flutes' (they come first on every dexel). The move turns past kMaxPieceTurn, so it is
    // swept in two pieces, both pieces' flutes before their shanks.
    const double turn = 20.0 * std::acos(-1.0) / 180.0;
    const Vec3& tip = kTurnTip;
    const ToolTable table = flutedD6();
    const ToolPath p = turnAboutTip(turn, "tilt.ngc", 7);
    const Box block{Vec3(10.0, 10.0, 0.0), Vec3(40.0, 30.0, 30.0)};
    TriDexelStock s = TriDexelStock::fromBox(block, 0.25);
    const CutResult r = cutStock(s, p, table);

    // The oracle's volumes: the midpoint rule on 0.05 mm cells over the block's reach.
    REQUIRE(MovePieces(p, toolRegions(p, table), kDefaultTurnTolerance).size() == 4);
    double cut = 0.0, shank = 0.0;
    const double step = 0.05;
    for (double x = 15.0 + 0.5 * step; x < 36.0; x += step)
        for (double y = 16.5 + 0.5 * step; y < 23.5; y += step)
            for (double z = 10.0 + 0.5 * step; z < block.hi.z; z += step) {
                const double X = x - tip.x, Y = y - tip.y, Z = z - tip.z;
                const bool flutes = inTurningCylinder(X, Y, Z, 3.0, 0.0, 10.0, 0.0, turn);
                const bool stick = inTurningCylinder(X, Y, Z, 3.0, 10.0, 40.0, 0.0, turn);
                cut += (flutes || stick) ? 1.0 : 0.0;
                shank += (stick && !flutes) ? 1.0 : 0.0;
            }
    cut *= step * step * step;
    shank *= step * step * step;
    INFO("oracle: removed " << cut << " mm^3, met by the shank " << shank << " mm^3; cut: removed "
                            << r.removedVolume << ", shank " << r.shankVolume);
    REQUIRE(shank > 100.0);
    REQUIRE(r.collisions.size() == 1);
    CHECK(r.collisions[0].kind == CollisionKind::Shank);
    CHECK(r.collisions[0].move == 0);
    CHECK(r.collisions[0].source.line == 7);
    CHECK(r.collisions[0].volume == Approx(shank).epsilon(0.005));  // measured: 0.04 %
    CHECK(r.removedVolume == Approx(cut).epsilon(0.005));  // measured: 0.02 %
}

TEST_CASE("a move turning 120 degrees is swept in twelve pieces whose union is its fan", "[stock][cut][turning]") {
    // The flat D6 of the test above turns 120 degrees about its tip, from +z towards +x and down
    // into the block: twelve pieces of kMaxPieceTurn, each its own sweep, together the fan of the
    // closed form.
    const double turn = 120.0 * std::acos(-1.0) / 180.0;
    const Vec3& tip = kTurnTip;
    const ToolTable table = flutedD6();
    const ToolPath p = turnAboutTip(turn, "fan.ngc", 3);
    // Twelve pieces of the flutes, then twelve of the shank.
    REQUIRE(MovePieces(p, toolRegions(p, table), kDefaultTurnTolerance).size() == 24);
    const Box block{Vec3(10.0, 10.0, 0.0), Vec3(40.0, 30.0, 30.0)};
    TriDexelStock s = TriDexelStock::fromBox(block, 0.25);
    const CutResult r = cutStock(s, p, table);
    // The oracle's volume: the midpoint rule on 0.1 mm cells over the block's reach.
    double cut = 0.0;
    const double step = 0.1;
    for (double x = block.lo.x + 0.5 * step; x < block.hi.x; x += step)
        for (double y = 16.5 + 0.5 * step; y < 23.5; y += step)
            for (double z = block.lo.z + 0.5 * step; z < block.hi.z; z += step)
                cut += inTurningCylinder(x - tip.x, y - tip.y, z - tip.z, 3.0, 0.0, 40.0, 0.0, turn) ? 1.0 : 0.0;
    cut *= step * step * step;
    INFO("oracle " << cut << " mm^3, cut " << r.removedVolume << " mm^3");
    REQUIRE(r.moves.size() == 1);
    CHECK(r.moves[0].removed == Approx(r.removedVolume));
    CHECK(r.removedVolume == Approx(cut).epsilon(0.001));  // measured: 0.003 %
}
