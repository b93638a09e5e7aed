// Tests of the G-code reader where a position is unknown: before the program states X, Y and Z,
// after G28, G30 or G53 to a machine position it never states, in G91 from such a position, and
// in canned cycles begun at an unknown level. Such moves only place the tool and are not swept;
// the expected places and warnings follow LinuxCNC's rules, worked out by hand.
#include <catch2/catch.hpp>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "dexelmill/path/gcode.h"
#include "support/gcode_run.h"

using namespace dexelmill;
using testing::findDiagnostic;
using testing::hasDiagnostic;
using testing::near;
using testing::runGcode;

TEST_CASE("gcode: with no start position, moves only place the tool until X, Y and Z are known", "[path]") {
    const Program p = parseGcode("G21 G90\nG0 Z15\nG0 X5 Y15\nG1 Z7 F100\nG1 X35\n", "start.ngc");
    REQUIRE(p.path.moves.size() == 2);
    CHECK(near(p.path.moves[0].start, Vec3(5, 15, 15)));
    CHECK(near(p.path.moves[0].end, Vec3(5, 15, 7)));
    CHECK(p.path.moves[0].source.line == 4);
    bool warned = false;
    for (const Diagnostic& d : p.diagnostics) warned = warned || d.message.find("start position is unknown") != std::string::npos;
    CHECK(warned);
}

TEST_CASE("gcode: G28, G30 and G53 to a machine position the program does not state are not swept",
          "[path][gcode]") {
    SECTION("G28 with #5161..#5163 never set: Z goes to the machine's own home, unknown here") {
        const Program p = runGcode("G0 X1 Y2 Z10\nG1 Z-1 F100\nG28 Z20\nG0 X5\nG0 Y6 Z7\nG1 X8\n");
        // Line 3 moves to the intermediate point (1, 2, 20), which the program states, and then
        // Z home, which it does not: neither that move nor line 4 is swept, and line 5 gives Z
        // again and only places the tool, at (5, 6, 7).
        const auto& m = p.path.moves;
        REQUIRE(m.size() == 4);
        CHECK(near(m[2].start, Vec3(1, 2, -1)));
        CHECK(near(m[2].end, Vec3(1, 2, 20)));
        CHECK(m[2].source.line == 3);
        CHECK(near(m[3].start, Vec3(5, 6, 7)));
        CHECK(near(m[3].end, Vec3(8, 6, 7)));
        CHECK(m[3].source.line == 6);
        const Diagnostic* d = findDiagnostic(p, "G28 moves Z to the stored position (#5163)");
        REQUIRE(d);
        CHECK(d->where.file == "test.ngc");
        CHECK(d->where.line == 3);
        CHECK(d->where.column == 1);
        const Diagnostic* lost = findDiagnostic(p, "position is unknown since a move");
        REQUIRE(lost);
        CHECK(lost->where.line == 4);
        // Left out, and counted: line 3's move to Z home, and lines 4 and 5.
        CHECK(p.movesNotSimulated == 3);
        // Without a start, the first move only places the tool too; a second program's count adds.
        Program unstarted = runGcode("G0 X1 Y2 Z10\nG1 Z-1 F100\n", GcodeOptions{});
        CHECK(unstarted.path.moves.size() == 1);
        CHECK(unstarted.movesNotSimulated == 1);
        unstarted.append(runGcode("G0 X1 Y2 Z10\nG1 Z-1 F100\nG28 Z20\nG0 X5\nG0 Y6 Z7\nG1 X8\n"));
        CHECK(unstarted.movesNotSimulated == 4);
    }
    SECTION("G28 and G30 to positions the program states go through the intermediate point") {
        // Under a work offset the program states, as a machine position needs (G53 too).
        const Program p = runGcode("G10 L2 P1 X0 Y0 Z0\n#5161 = 1 #5162 = 2 #5163 = 3\nG0 X4 Y5 Z6\nG30.1\n"
                              "G0 X0 Y0 Z9\nG30 Z20\nG28\nG91 G28 X0\n");
        const auto& m = p.path.moves;
        REQUIRE(m.size() == 7);
        CHECK(near(m[2].end, Vec3(0, 0, 20)));  // G30's intermediate point
        CHECK(near(m[3].end, Vec3(0, 0, 6)));   // then Z alone to the stored Z
        CHECK(near(m[4].end, Vec3(1, 2, 3)));   // G28 without axes: straight to #5161..#5163
        CHECK(near(m[5].end, Vec3(1, 2, 3)));   // G91: the intermediate point is here
        CHECK(near(m[6].end, Vec3(1, 2, 3)));
        for (const Move& mv : m) CHECK(mv.rapid);
        CHECK_FALSE(hasDiagnostic(p, "stored position"));
    }
    SECTION("G28.1 stores only the coordinates known where it stands") {
        const Program p = parseGcode("G10 L2 P1 X0 Y0 Z0\nG0 X1 Y2\nG28.1\nG0 Z5\nG1 X3 F100\nG28\nG1 X4\n",
                                     "home.ngc");
        // Line 4 makes the position known at (1, 2, 5); line 5 cuts; G28 sends Z to an unknown place.
        const auto& m = p.path.moves;
        REQUIRE(m.size() == 1);
        CHECK(near(m[0].end, Vec3(3, 2, 5)));
        const Diagnostic* d = findDiagnostic(p, "G28 moves Z to the stored position (#5163)");
        REQUIRE(d);
        CHECK(d->where.line == 6);
    }
    SECTION("G53 without the active work offset stated") {
        const Program p = runGcode("G10 L2 P1 X100\nG55 G0 X0 Y0 Z10\nG53 G0 Z0\nG0 X5 Y5\nG0 Z5\nG1 X6 F100\n");
        const auto& m = p.path.moves;
        REQUIRE(m.size() == 2);
        CHECK(near(m[0].end, Vec3(0, 0, 10)));
        CHECK(near(m[1].start, Vec3(5, 5, 5)));
        CHECK(near(m[1].end, Vec3(6, 5, 5)));
        const Diagnostic* d = findDiagnostic(p, "G53 moves Z in machine coordinates");
        REQUIRE(d);
        CHECK(d->message.find("G55 work offset") != std::string::npos);
        CHECK(d->where.line == 3);
        CHECK(d->where.column == 1);
    }
    SECTION("G53 with the work offset stated (G10 L2) is swept") {
        const Program p = runGcode("G10 L2 P1 X-100 Y0 Z-50\nG54 G0 X0 Y0 Z10\nG53 G0 Z0\nG53 X-50\n");
        const auto& m = p.path.moves;
        REQUIRE(m.size() == 3);
        CHECK(near(m[0].end, Vec3(-100, 0, -40)));
        CHECK(near(m[1].end, Vec3(-100, 0, 0)));
        CHECK(near(m[2].end, Vec3(-50, 0, 0)));
        CHECK_FALSE(hasDiagnostic(p, "G53 moves"));
    }
}

TEST_CASE("gcode: G91 moves from an unknown position leave it unknown", "[path][gcode]") {
    SECTION("no sweep from a guessed origin") {
        // Line 2 would reach (5, 5, 5) from a guessed origin: no coordinate becomes known until
        // line 5 states Z and line 6 X and Y in G90; line 7 is the first move swept.
        const Program p = parseGcode("G21 G91\nG0 X5 Y5 Z5\nG1 Z-10 F100\nG1 X20\nG90 G0 Z3\nG0 X1 Y2\nG1 Z-1\n",
                                     "inc.ngc");
        REQUIRE(p.path.moves.size() == 1);
        CHECK(near(p.path.moves[0].start, Vec3(1, 2, 3)));
        CHECK(near(p.path.moves[0].end, Vec3(1, 2, -1)));
        CHECK(p.path.moves[0].source.line == 7);
        const Diagnostic* d = findDiagnostic(p, "incremental (G91) X from a position where X is unknown");
        REQUIRE(d);
        CHECK(d->where.line == 2);
        CHECK(d->where.column == 4);
    }
    SECTION("a known axis stays known in G91, an unknown one does not become known") {
        const Program p = parseGcode("G0 X1 Y2\nG91 G0 X1 Z1\nG90 G0 Z4\nG91 G1 X1 Y1 F100\n", "inc.ngc");
        // X and Y are known from line 1 (X moves on to 2 in G91); Z only from line 3.
        REQUIRE(p.path.moves.size() == 1);
        CHECK(near(p.path.moves[0].start, Vec3(2, 2, 4)));
        CHECK(near(p.path.moves[0].end, Vec3(3, 3, 4)));
    }
    SECTION("G92 names the present point: an old-style program's start") {
        const Program p = parseGcode("G92 X0 Y0 Z0\nG91 G1 Z-1 F100\nG1 X10\n", "g92.ngc");
        REQUIRE(p.path.moves.size() == 2);
        CHECK(near(p.path.moves[0].start, Vec3(0, 0, 0)));
        CHECK(near(p.path.moves[0].end, Vec3(0, 0, -1)));
        CHECK(near(p.path.moves[1].end, Vec3(10, 0, -1)));
        CHECK_FALSE(hasDiagnostic(p, "unknown"));
        // Under a work offset the program states, the present point is named in its frame.
        const Program q = parseGcode("G10 L2 P1 X100\nG92 X5 Y0 Z0\nG1 X6 F100\n", "g92.ngc");
        REQUIRE(q.path.moves.size() == 1);
        CHECK(near(q.path.moves[0].start, Vec3(105, 0, 0)));
        CHECK(near(q.path.moves[0].end, Vec3(106, 0, 0)));
    }
    SECTION("G10 L20 on the active system names the present point, as G92 does") {
        // Touched off where the operator put the tool: the incremental moves after it are cut.
        const Program p = parseGcode("G10 L20 P0 X0 Y0 Z0\nG91 G1 Z-1 F100\nX20\n", "l20.ngc");
        REQUIRE(p.path.moves.size() == 2);
        CHECK(near(p.path.moves[0].start, Vec3(0, 0, 0)));
        CHECK(near(p.path.moves[0].end, Vec3(0, 0, -1)));
        CHECK(near(p.path.moves[1].end, Vec3(20, 0, -1)));
        CHECK_FALSE(hasDiagnostic(p, "unknown"));
        // On another system than the active one it names nothing here: Z stays unknown.
        const Program q = parseGcode("G0 X0 Y0\nG10 L20 P2 Z0\nG91 G1 Z-1 F100\nG90 X5\n", "l20.ngc");
        CHECK(q.path.moves.empty());
        CHECK(hasDiagnostic(q, "incremental (G91) Z from a position where Z is unknown"));
    }
    SECTION("G28 G91 Z0 at the start warns of the stored position, not of a G91 move") {
        // The point on the way is never reached as a place of its own: Z goes on home. The one
        // warning is G28's; a later incremental move from an unknown Z still gets its own.
        const Program p = parseGcode("G28 G91 Z0\nG90 G0 X0 Y0\nG91 G1 Z-1 F100\n", "home.ngc");
        CHECK(p.path.moves.empty());
        const Diagnostic* g28 = findDiagnostic(p, "G28 moves Z to the stored position");
        REQUIRE(g28);
        CHECK(g28->where.line == 1);
        const Diagnostic* inc = findDiagnostic(p, "incremental (G91) Z from a position where Z is unknown");
        REQUIRE(inc);
        CHECK(inc->where.line == 3);
    }
    SECTION("an arc from an unknown start only places the tool at its end") {
        // Its centre and radius hang on the start, which is unknown: the radius check is not made
        // against a guessed start (from (0, 0) the radii would be 3 and 7; from (4, 0), say, the
        // arc is good), and no chord is swept.
        const Program p = parseGcode("G0 Z5\nG2 X10 Y0 I3 J0\nG1 X11 F100\n", "arc.ngc");
        REQUIRE(p.path.moves.size() == 1);
        CHECK(near(p.path.moves[0].start, Vec3(10, 0, 5)));
        CHECK(near(p.path.moves[0].end, Vec3(11, 0, 5)));
        CHECK_FALSE(hasDiagnostic(p, "has no effect"));
    }
}

TEST_CASE("gcode: canned cycles from an unknown level sweep only what they state", "[path][gcode]") {
    SECTION("G98 retracts to an unknown level: the holes are swept, the retracts and travels are not") {
        const Program p = parseGcode("G0 X0 Y0\nG98 G81 X10 Y0 Z-5 R2 F100\nX20\nG80\nG0 Z10\nG1 X30\n", "g98.ngc");
        const auto& m = p.path.moves;
        REQUIRE(m.size() == 3);
        CHECK(near(m[0].start, Vec3(10, 0, 2)));
        CHECK(near(m[0].end, Vec3(10, 0, -5)));
        CHECK_FALSE(m[0].rapid);
        CHECK(near(m[1].start, Vec3(20, 0, 2)));
        CHECK(near(m[1].end, Vec3(20, 0, -5)));
        CHECK(m[1].source.line == 3);
        CHECK(near(m[2].start, Vec3(20, 0, 10)));
        CHECK(near(m[2].end, Vec3(30, 0, 10)));
        const Diagnostic* d = findDiagnostic(p, "G98 retracts to the Z where the cycle began, which is unknown");
        REQUIRE(d);
        CHECK(d->where.line == 2);
        CHECK(d->where.column == 5);
    }
    SECTION("G99 retracts to R, which is known: only the way to the first hole is not swept") {
        const Program p = parseGcode("G0 X0 Y0\nG99 G81 X10 Y0 Z-5 R2 F100\nX20\n", "g99.ngc");
        const std::vector<std::pair<Vec3, Vec3>> expected = {{{10, 0, 2}, {10, 0, -5}}, {{10, 0, -5}, {10, 0, 2}},
                                                            {{10, 0, 2}, {20, 0, 2}},  {{20, 0, 2}, {20, 0, -5}},
                                                            {{20, 0, -5}, {20, 0, 2}}};
        const auto& m = p.path.moves;
        REQUIRE(m.size() == expected.size());
        for (std::size_t k = 0; k < m.size(); ++k) {
            INFO("move " << k);
            CHECK(near(m[k].start, expected[k].first));
            CHECK(near(m[k].end, expected[k].second));
        }
        CHECK_FALSE(hasDiagnostic(p, "G98 retracts"));
    }
    SECTION("in G91 the R plane and the depth count from the unknown level: nothing is swept") {
        const Program p = parseGcode("G0 X0 Y0\nG91 G81 X10 Z-5 R-2 F100\nX10\nG90 G80 G0 Z5\nG1 X25\n", "g91.ngc");
        // X stays known through the cycle (0 + 10 + 10); Z is known again at line 4.
        REQUIRE(p.path.moves.size() == 1);
        CHECK(near(p.path.moves[0].start, Vec3(20, 0, 5)));
        CHECK(near(p.path.moves[0].end, Vec3(25, 0, 5)));
        const Diagnostic* d = findDiagnostic(p, "canned cycle in G91 from an unknown Z");
        REQUIRE(d);
        CHECK(d->where.line == 2);
        CHECK(d->where.column == 5);
    }
}
