// Tests of the G-code reader's offsets: which machine positions and offset changes leave the
// position known on the part, G53 under a tool length offset and with rotary words, and the work
// offsets' parameters. The expected places are worked out by hand from LinuxCNC's rules.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "dexelmill/machine/kinematics.h"
#include "dexelmill/path/gcode.h"
#include "support/gcode_run.h"

using namespace dexelmill;

using testing::findDiagnostic;
using testing::kPlaceTol;
using testing::linuxcnc;
using testing::near;
using testing::runGcode;

TEST_CASE("gcode offsets: an offset change after G92 named an unknown point leaves the axes unknown",
          "[path][gcode]") {
    SECTION("G92.1 after G92 X0 Y0 Z0 at the start") {
        // Lines 2 and 3 cut from the named point; G92.1 drops an offset taken from a guessed
        // machine position, so line 5's X0 is somewhere unknown on the part: not swept.
        const Program p = parseGcode("G92 X0 Y0 Z0\nG91 G1 Z-1 F100\nG1 X10\nG92.1\nG90 G1 X0\n", "g92.ngc");
        const auto& m = p.path.moves;
        REQUIRE(m.size() == 2);
        CHECK(near(m[1].end, Vec3(10, 0, -1)));
        const Diagnostic* d = findDiagnostic(p, "G92.1 changes the offset of X, Y, Z");
        REQUIRE(d);
        CHECK(d->where.line == 4);
        CHECK(d->where.column == 1);
    }
    SECTION("G92.1 where nothing was guessed keeps the position") {
        // At X0, G92 X10 makes the offset -10; G92.1 clears it: X0 again, and X5 is machine X5.
        const Program p = runGcode("G0 X0 Y0 Z0\nG92 X10\nG92.1\nG1 X5 F100\n");
        const auto& m = p.path.moves;
        REQUIRE(m.size() == 2);
        CHECK(near(m[1].start, Vec3(0, 0, 0)));
        CHECK(near(m[1].end, Vec3(5, 0, 0)));
        CHECK_FALSE(findDiagnostic(p, "changes the offset"));
    }
    SECTION("G10 L2 on the active system after G10 L20 named an unknown point") {
        // X is lost at line 3 and placed again in the new frame at line 4 (machine X56), not
        // swept there; line 5 is, Y and Z having stayed in the frame the guess set.
        const Program p = parseGcode("G10 L20 P0 X0 Y0 Z0\nG1 X5 F100\nG10 L2 P1 X50\nG1 X6\nG1 Y1\n", "l20.ngc");
        REQUIRE(p.path.moves.size() == 2);
        CHECK(near(p.path.moves[0].end, Vec3(5, 0, 0)));
        CHECK(near(p.path.moves[1].start, Vec3(56, 0, 0)));
        CHECK(near(p.path.moves[1].end, Vec3(56, 1, 0)));
        const Diagnostic* d = findDiagnostic(p, "G10 L2 changes the offset of X,");
        REQUIRE(d);
        CHECK(d->where.line == 3);
    }
    SECTION("switching from a system whose offset was guessed") {
        const Program p = parseGcode("G10 L20 P0 X0 Y0 Z0\nG1 X5 F100\nG55\nG1 X6\n", "l20.ngc");
        REQUIRE(p.path.moves.size() == 1);
        const Diagnostic* d = findDiagnostic(p, "G55 changes the offset of X, Y, Z");
        REQUIRE(d);
        CHECK(d->where.line == 3);
    }
    SECTION("G53 after G92 named an unknown point, though G54's offset is stated") {
        const Program p = parseGcode("G10 L2 P1 X0 Y0 Z0\nG92 X0 Y0 Z0\nG1 X5 F100\nG53 G0 Z0\nG1 X6\n", "g92.ngc");
        REQUIRE(p.path.moves.size() == 1);
        CHECK(near(p.path.moves[0].end, Vec3(5, 0, 0)));
        const Diagnostic* d = findDiagnostic(p, "G53 moves Z in machine coordinates");
        REQUIRE(d);
        CHECK(d->message.find("guessed machine position") != std::string::npos);
        CHECK(d->where.line == 4);
    }
}

TEST_CASE("gcode offsets: a stated G28 position is a place on the part only under a stated offset",
          "[path][gcode]") {
    SECTION("#5163 set, G54's offset not") {
        // Line 4 goes through (1, 2, 20), then to machine Z3, which the unstated G54 offset does
        // not place on the part: that move and line 5 are not swept.
        const Program p = runGcode("#5163 = 3\nG0 X1 Y2 Z10\nG1 Z-1 F100\nG28 Z20\nG1 X5\n");
        const auto& m = p.path.moves;
        REQUIRE(m.size() == 3);
        CHECK(near(m[2].end, Vec3(1, 2, 20)));
        const Diagnostic* d = findDiagnostic(p, "G28 moves Z to the stored position (#5163), a machine position");
        REQUIRE(d);
        CHECK(d->message.find("G54 work offset") != std::string::npos);
        CHECK(d->where.line == 4);
    }
    SECTION("#5163 and G54's Z offset both set") {
        // G54's Z offset -10: the way point Z20 is machine Z10, home machine Z3 (part Z13).
        const Program p = runGcode("G10 L2 P1 Z-10\n#5163 = 3\nG0 X1 Y2 Z10\nG28 Z20\nG1 X5 F100\n");
        const auto& m = p.path.moves;
        REQUIRE(m.size() == 4);
        CHECK(near(m[1].end, Vec3(1, 2, 10)));
        CHECK(near(m[2].end, Vec3(1, 2, 3)));
        CHECK(near(m[3].end, Vec3(5, 2, 3)));
        CHECK_FALSE(findDiagnostic(p, "G28 moves"));
    }
}

TEST_CASE("gcode offsets: under G43 a machine Z is the gauge line, not the tip", "[path][gcode]") {
    // LinuxCNC's G53 takes the tool length offset off as it does the work offsets: G53 Z50 puts
    // the spindle's gauge line at machine Z50 and the tip a tool length below.
    const Program p = runGcode("G10 L2 P1 X0 Y0 Z0\nG0 X0 Y0 Z10\nG43 H1\nG53 G0 Z50\nG1 X5 F100\n");
    REQUIRE(p.path.moves.size() == 1);
    const Diagnostic* d = findDiagnostic(p, "G53 moves Z in machine coordinates");
    REQUIRE(d);
    CHECK(d->message.find("gauge line") != std::string::npos);
    CHECK(d->where.line == 4);
    // After G49 the tip is the point G53 names.
    const Program q = runGcode("G10 L2 P1 X0 Y0 Z0\nG0 X0 Y0 Z10\nG43 H1\nG49\nG53 G0 Z50\nG1 X5 F100\n");
    REQUIRE(q.path.moves.size() == 3);
    CHECK(near(q.path.moves[1].end, Vec3(0, 0, 50)));
    CHECK(near(q.path.moves[2].end, Vec3(5, 0, 50)));
    // G28's stored Z is a machine position too.
    const Program h = runGcode("G10 L2 P1 X0 Y0 Z0\n#5163 = 40\nG0 X0 Y0 Z10\nG43 H1\nG28 Z10\n");
    const Diagnostic* g28 = findDiagnostic(h, "G28 moves Z to the stored position (#5163), a machine position");
    REQUIRE(g28);
    CHECK(g28->message.find("gauge line") != std::string::npos);
}

TEST_CASE("gcode offsets: G53's rotary words are machine angles, without the work offsets", "[path][gcode]") {
    GcodeOptions o = linuxcnc();
    o.machine = loadMachine("xyzac-trt");
    // G54's C offset 30: C0 turns C to machine 30; G53 C10 to machine 10, not 40.
    const Program p = runGcode("G10 L2 P1 X0 Y0 Z0 C30\nG0 X0 Y0 Z50 C0\nG53 G0 C10\n", o);
    const Interval& c = p.rotaryRanges[2];
    CHECK(c.lo == Approx(0.0).margin(kPlaceTol));
    CHECK(c.hi == Approx(30.0).margin(kPlaceTol));
    REQUIRE(p.path.moves.size() == 2);
}

TEST_CASE("gcode offsets: a work offset's parameters take effect when the system is selected",
          "[path][gcode]") {
    // LinuxCNC loads a system's offsets from #5221 + 20 k .. when the program selects it; the
    // active system is not reloaded by selecting it again.
    const Program p = runGcode("#5241 = 100 #5242 = 0 #5243 = -20\nG55\nG0 X0 Y0 Z0\nG53 G0 Z0\n");
    const auto& m = p.path.moves;
    REQUIRE(m.size() == 2);
    CHECK(near(m[0].end, Vec3(100, 0, -20)));
    CHECK(near(m[1].end, Vec3(100, 0, 0)));  // the parameters state the offset: G53 is swept
    CHECK_FALSE(findDiagnostic(p, "G53 moves"));
    const Program q = runGcode("#5221 = 100\nG54 G0 X0 Y0 Z0\nG55\nG54\nG0 X0\n");
    REQUIRE(q.path.moves.size() == 2);
    CHECK(near(q.path.moves[0].end, Vec3(0, 0, 0)));
    CHECK(near(q.path.moves[1].end, Vec3(100, 0, 0)));
    // The rotary offsets too (#5246, G55's C): C0 there is machine C30.
    GcodeOptions o = linuxcnc();
    o.machine = loadMachine("xyzac-trt");
    const Program r = runGcode("#5246 = 30\nG55\nG0 X0 Y0 Z50 C0\n", o);
    CHECK(r.rotaryRanges[2].hi == Approx(30.0).margin(kPlaceTol));
}
