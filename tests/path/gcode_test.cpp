// Tests of the G-code reader: real programs, LinuxCNC canon references, semantics, errors.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "dexelmill/error.h"
#include "dexelmill/path/gcode.h"
#include "path/testdata.h"

using namespace dexelmill;

namespace {

using test::haveSharedData;
using test::sharedData;

Program run(const std::string& text, GcodeOptions options = {}) {
    return parseGcode(text, "test.ngc", options);
}

bool near(const Vec3& a, const Vec3& b, double tol = 1e-9) {
    return std::abs(a.x - b.x) <= tol && std::abs(a.y - b.y) <= tol && std::abs(a.z - b.z) <= tol;
}

bool hasDiagnostic(const Program& p, const std::string& fragment) {
    for (const Diagnostic& d : p.diagnostics)
        if (d.message.find(fragment) != std::string::npos) return true;
    return false;
}

}  // namespace

TEST_CASE("gcode: every G-code program of the shared testdata parses", "[path][gcode]") {
    if (!haveSharedData()) return;
    namespace fs = std::filesystem;
    int count = 0;
    for (const auto& entry : fs::recursive_directory_iterator(sharedData())) {
        const std::string ext = entry.path().extension().string();
        if (ext != ".nc" && ext != ".ngc" && ext != ".gcode") continue;
        const std::string path = entry.path().string();
        const bool rotary = path.find("5axis-xyzac") != std::string::npos ||
                            path.find("rotation.ngc") != std::string::npos;
        INFO(path);
        if (rotary) {
            // A/C and A programs need machine kinematics: a clear error, not a wrong path.
            try {
                readGcode(path);
                FAIL("expected a rotary-axis error");
            } catch (const ParseError& e) {
                CHECK(std::string(e.what()).find("rotary") != std::string::npos);
                CHECK(e.where().line > 0);
            }
            continue;
        }
        Program p;
        REQUIRE_NOTHROW(p = readGcode(path));
        ++count;
    }
    CHECK(count >= 20);
}
