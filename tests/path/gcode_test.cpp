// Tests of the G-code reader: real programs, LinuxCNC canon references, semantics, errors.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
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

namespace {

/// A motion call of a LinuxCNC canon file: its kind and end point in program units.
struct CanonMotion {
    enum Kind { Traverse, Feed, Arc } kind;
    double end[3];
    double scale;  ///< mm per program unit when the call was made
    int line;
};

std::vector<CanonMotion> readCanon(const std::string& path) {
    std::ifstream in(path);
    std::vector<CanonMotion> out;
    std::string line;
    double scale = 1.0;
    int plane = 17;
    int number = 0;
    while (std::getline(in, line)) {
        ++number;
        if (line.find("USE_LENGTH_UNITS(CANON_UNITS_INCHES)") != std::string::npos) scale = 25.4;
        if (line.find("USE_LENGTH_UNITS(CANON_UNITS_MM)") != std::string::npos) scale = 1.0;
        if (line.find("SELECT_PLANE(CANON_PLANE_XY)") != std::string::npos) plane = 17;
        if (line.find("SELECT_PLANE(CANON_PLANE_XZ)") != std::string::npos) plane = 18;
        if (line.find("SELECT_PLANE(CANON_PLANE_YZ)") != std::string::npos) plane = 19;
        const char* kinds[] = {"STRAIGHT_TRAVERSE(", "STRAIGHT_FEED(", "ARC_FEED("};
        for (int k = 0; k < 3; ++k) {
            const auto p = line.find(kinds[k]);
            if (p == std::string::npos) continue;
            std::vector<double> v;
            std::stringstream ss(line.substr(p + std::strlen(kinds[k])));
            std::string item;
            while (std::getline(ss, item, ',')) v.push_back(std::stod(item));
            CanonMotion m{CanonMotion::Kind(k), {0, 0, 0}, scale, number};
            if (k < 2) {
                m.end[0] = v.at(0), m.end[1] = v.at(1), m.end[2] = v.at(2);
            } else {
                // ARC_FEED(first_end, second_end, first_axis, second_axis, rotation, axis_end...)
                const double first = v.at(0), second = v.at(1), axisEnd = v.at(5);
                if (plane == 17) m.end[0] = first, m.end[1] = second, m.end[2] = axisEnd;
                if (plane == 18) m.end[2] = first, m.end[0] = second, m.end[1] = axisEnd;
                if (plane == 19) m.end[1] = first, m.end[2] = second, m.end[0] = axisEnd;
            }
            out.push_back(m);
        }
    }
    return out;
}

/// Our coordinate printed as the canon prints it (4 decimals, program units) and read back.
double asCanon(double mm, double scale) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.4f", mm / scale);
    return std::stod(buf);
}

bool matchesCanon(const Vec3& p, const CanonMotion& c) {
    for (int a = 0; a < 3; ++a)
        if (std::abs(asCanon(p[a], c.scale) - c.end[a]) > 1e-6) return false;
    return true;
}

/// Walks the canon motions and our moves together: a straight call is one move of the same kind
/// ending at the same point; an arc call is a run of feed moves from one source line whose last
/// move ends at the arc's end.
void checkAgainstCanon(const Program& p, const std::vector<CanonMotion>& canon) {
    const auto& moves = p.path.moves;
    std::size_t m = 0;
    for (const CanonMotion& c : canon) {
        INFO("canon line " << c.line);
        REQUIRE(m < moves.size());
        if (c.kind != CanonMotion::Arc) {
            INFO("move " << m << " from program line " << moves[m].source.line << " ends at "
                         << moves[m].end.x << ", " << moves[m].end.y << ", " << moves[m].end.z);
            CHECK(moves[m].rapid == (c.kind == CanonMotion::Traverse));
            REQUIRE(matchesCanon(moves[m].end, c));
            ++m;
            continue;
        }
        const int line = moves[m].source.line;
        while (m < moves.size() && !moves[m].rapid && moves[m].source.line == line &&
               !matchesCanon(moves[m].end, c))
            ++m;
        REQUIRE(m < moves.size());
        CHECK_FALSE(moves[m].rapid);
        REQUIRE(matchesCanon(moves[m].end, c));
        ++m;
    }
    CHECK(m == moves.size());
}

}  // namespace

TEST_CASE("gcode: LinuxCNC canon references of canned cycles and M98 loops", "[path][gcode][canon]") {
    if (!haveSharedData()) return;
    const std::string base = sharedData() + "/linuxcnc/";
    for (const char* name : {"g81-cycles/g17-g98-g81", "g81-cycles/g18-g98-g81",
                             "g81-cycles/g19-g98-g81", "fanuc-subs/05-M98-loops"}) {
        INFO(name);
        const Program p = readGcode(base + name + ".ngc");
        const auto canon = readCanon(base + name + ".expected.canon");
        REQUIRE(canon.size() > 10);
        checkAgainstCanon(p, canon);
    }
}

TEST_CASE("gcode: cam-nisley O-word program against its canon (cutter comp aside)", "[path][gcode][canon]") {
    if (!haveSharedData()) return;
    const std::string base = sharedData() + "/linuxcnc/cam-nisley/";
    GcodeOptions options;
    options.toolTableFile = base + "test.tbl";
    options.toolTableInches = true;
    const Program p = readGcode(base + "cam.ngc", options);
    const auto canon = readCanon(base + "cam.expected.canon");
    CHECK(hasDiagnostic(p, "cutter radius compensation"));
    REQUIRE(p.tools.count(1) == 1);
    // LinuxCNC applied G42 with the table's 1/16" cutter, which this reader warns about and
    // does not simulate: compare the programmed path where comp does not move it: Z of every
    // call, and every coordinate of the moves made before comp starts and after it ends.
    const auto& moves = p.path.moves;
    std::size_t m = 0;
    std::size_t compared = 0;
    for (std::size_t k = 0; k < canon.size(); ++k) {
        const CanonMotion& c = canon[k];
        INFO("canon line " << c.line << ", move " << m);
        REQUIRE(m < moves.size());
        if (c.kind != CanonMotion::Arc) {
            CHECK(moves[m].rapid == (c.kind == CanonMotion::Traverse));
            CHECK(std::abs(asCanon(moves[m].end.z, c.scale) - c.end[2]) <= 1e-6);
            if (k < 2 || k + 1 == canon.size()) {
                CHECK(matchesCanon(moves[m].end, c));
                ++compared;
            }
            ++m;
            continue;
        }
        const int line = moves[m].source.line;
        while (m + 1 < moves.size() && moves[m + 1].source.line == line && !moves[m + 1].rapid) ++m;
        CHECK(std::abs(asCanon(moves[m].end.z, c.scale) - c.end[2]) <= 1e-6);
        ++m;
    }
    CHECK(m == moves.size());
    CHECK(compared == 3);
}
