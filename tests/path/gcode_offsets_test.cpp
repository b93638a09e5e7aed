// Tests of the G-code reader's offsets. The expected places are worked out by hand from
// LinuxCNC's rules.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "dexelmill/machine/kinematics.h"
#include "dexelmill/path/gcode.h"

using namespace dexelmill;

namespace {

/// Options as LinuxCNC runs a program: the machine starts at the origin.
GcodeOptions linuxcnc() {
    GcodeOptions o;
    o.startPosition = Vec3(0.0);
    return o;
}

Program run(const std::string& text, GcodeOptions options = linuxcnc()) {
    return parseGcode(text, "offsets.ngc", options);
}

/// Places (mm) and angles (degrees) worked out by hand: equal up to the rounding of a few operations.
constexpr double kTol = 1e-9;

}  // namespace

TEST_CASE("gcode offsets: G53's rotary words are machine angles, without the work offsets", "[path][gcode]") {
    GcodeOptions o = linuxcnc();
    o.machine = loadMachine("xyzac-trt");
    // G54's C offset 30: C0 turns C to machine 30; G53 C10 to machine 10, not 40.
    const Program p = run("G10 L2 P1 X0 Y0 Z0 C30\nG0 X0 Y0 Z50 C0\nG53 G0 C10\n", o);
    const Interval& c = p.rotaryRanges[2];
    CHECK(c.lo == Approx(0.0).margin(kTol));
    CHECK(c.hi == Approx(30.0).margin(kTol));
    REQUIRE(p.path.moves.size() == 2);
}
