// Tests of the G-code reader: real programs, LinuxCNC canon references, semantics, errors.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "dexelmill/error.h"
#include "dexelmill/path/gcode.h"
#include "support/gcode_run.h"
#include "testdata.h"

using namespace dexelmill;

namespace {

using test::haveSharedData;
using test::sharedData;
using testing::hasDiagnostic;
using testing::linuxcnc;
using testing::near;
using testing::runGcode;

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
        if (entry.path().filename().string().find("_switchkins.ngc") != std::string::npos) {
            // Calls a subroutine from LinuxCNC's remap folder, which the testdata does not ship.
            try {
                readGcode(path);
                FAIL("expected an undefined-subroutine error");
            } catch (const ParseError& e) {
                CHECK(std::string(e.what()).find("undefined subroutine") != std::string::npos);
                CHECK(e.where().line > 0);
            }
            continue;
        }
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
        const Program p = readGcode(base + name + ".ngc", linuxcnc());
        const auto canon = readCanon(base + name + ".expected.canon");
        REQUIRE(canon.size() > 10);
        checkAgainstCanon(p, canon);
    }
}

TEST_CASE("gcode: cam-nisley O-word program against its canon (cutter comp aside)", "[path][gcode][canon]") {
    if (!haveSharedData()) return;
    const std::string base = sharedData() + "/linuxcnc/cam-nisley/";
    GcodeOptions options;
    options.startPosition = Vec3(0.0);
    const Program p = readGcode(base + "cam.ngc", options);
    const auto canon = readCanon(base + "cam.expected.canon");
    CHECK(hasDiagnostic(p, "cutter radius compensation"));
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

namespace {

struct Malformed {
    const char* what;
    const char* text;
    int line;
    int column;           ///< 0: any
    const char* message;  ///< fragment of the message
    const char* offending;  ///< fragment of the offending text
};

}  // namespace

TEST_CASE("gcode: malformed programs give a parse error with file:line:col and the text",
          "[path][gcode][errors]") {
    const Malformed cases[] = {
        {"bad number", "G1 X1.2.3\n", 1, 5, "bad number", "1.2.3"},
        {"missing value", "G1 X\n", 1, 0, "missing value", ""},
        {"letter without number", "G1 XY2\n", 1, 5, "expected a number", "Y2"},
        {"two motion codes", "G0 G1 X1\n", 1, 4, "modal group", "G1"},
        {"two plane codes", "G17 G18\n", 1, 5, "modal group", "G18"},
        {"two unit codes", "G20 G21\n", 1, 5, "modal group", "G21"},
        {"G53 with G92", "G0 X0 Y0 Z0\nG53 G92 X5\n", 2, 5,
         "two G-codes from one modal group (group 0): LinuxCNC allows one per block", "G92"},
        {"G53 with G4", "G0 G53 G4 P1 X5\n", 1, 8, "modal group (group 0)", "G4"},
        {"two words of one letter", "G1 X1 X2\n", 1, 7, "two X words", "X2"},
        {"arc radius does not fit", "G0 X0 Y0\nG2 X10 Y0 R2\n", 2, 11, "radius too small", "R2"},
        {"arc end not on circle", "G0 X0 Y0\nG2 X10 Y0 I3 J0\n", 2, 1, "radius to end of arc differs", "G2"},
        // LinuxCNC's arc_data_ijk: 3 mm is within 0.1 % of 3003 mm but past 100 x 0.0283 mm.
        {"large arc end off by more than the cap", "G0 X0 Y0\nG2 X6003 Y0 I3000 J0\n", 2, 1,
         "LinuxCNC accepts a difference up to 0.0282843 mm, or up to 2.82843 mm", "G2"},
        {"arc without centre", "G0 X0 Y0\nG2 X10 Y0\n", 2, 1, "arc without", "G2"},
        // LinuxCNC's convert_arc: a centre word across the plane, and check_g_codes: G4 needs P.
        {"K word on a G17 arc", "G0 X0 Y0\nG2 X10 Y0 I5 K1\n", 2, 14, "K word given for an arc in the G17 plane", "K1"},
        {"J word on a G18 arc", "G0 X0 Z0\nG18 G3 X10 Z0 I5 J0\n", 2, 18, "J word given for an arc in the G18 plane", "J0"},
        {"I word on a G19 arc", "G0 Y0 Z0\nG19 G2 Y10 J5 I2\n", 2, 15, "I word given for an arc in the G19 plane", "I2"},
        {"dwell without a time", "G0 X0\nG4\n", 2, 1, "dwell time missing with G4", "G4"},
        {"absolute centre without J", "G0 X0 Y0\nG90.1\nG3 X20 Y0 I10\n", 3, 11,
         "J word missing in absolute center arc (G90.1): LinuxCNC needs both I and J in the G17 plane", "I10"},
        {"absolute centre without I in G18", "G18 G90.1\nG0 X0 Z0\nG2 X10 Z0 K0\n", 3, 11,
         "I word missing in absolute center arc", "K0"},
        {"dwell with an arc", "G0 X0 Y0\nG4 P2 G2 X10 Y0 I5\n", 2, 1, "G4 with G2 in one block: both use P", "G4"},
        {"R arc to itself", "G0 X1 Y1\nG2 X1 Y1 R5\n", 2, 10, "same start and end", "R5"},
        {"unterminated comment", "G0 X1 (rapid\n", 1, 7, "unterminated comment", "(rapid"},
        {"unterminated subroutine", "o100 sub\nG1 X1\n", 1, 1, "unterminated subroutine", "o100 sub"},
        {"unterminated while", "o1 while [1]\nG1 X1\n", 1, 1, "unterminated loop", "o1 while"},
        {"unterminated if", "o2 if [1]\nG1 X1\n", 1, 1, "unterminated if", "o2 if"},
        {"recursion without end", "o<r> sub\no<r> call\no<r> endsub\nG0 X0\no<r> call\nM2\n", 2, 1, "recursion", "o<r> call"},
        {"M98 recursion", "M98 P7\nM30\nO7\nM98 P7\nM99\n", 4, 0, "recursion", "M98"},
        {"endless loop", "o1 while [1]\nG0 X1\no1 endwhile\n", 3, 1, "ran twice without changing", "o1 endwhile"},
        {"endless do loop", "#1 = 0\no1 do\n#1 = 0\no1 while [#1 LT 10]\n", 4, 1, "ran twice without changing",
         "o1 while"},
        {"endless Fanuc loop", "WHILE [1] DO1\nG0 X1\nEND1\n", 3, 1, "ran twice without changing", "END1"},
        {"endless GOTO", "N10 G0 X1\nGOTO 10\n", 2, 1, "ran twice without changing", "GOTO 10"},
        {"endless continue", "o1 while [1]\no1 continue\no1 endwhile\n", 2, 1, "ran twice without changing",
         "o1 continue"},
        {"break after its loop", "#1 = 0\no1 do\n#1 = [#1 + 1]\no1 while [#1 LT 3]\no1 break\n", 5, 1,
         "outside a loop", "o1 break"},
        {"continue after its loop", "o1 repeat [2]\nG0 X1\no1 endrepeat\no1 continue\n", 4, 1, "outside a loop",
         "o1 continue"},
        {"loop that counts for ever", "#1 = 0\no1 while [1]\n#1 = [#1 + 1]\no1 endwhile\n", 2, 1,
         "more than 100000 blocks", "o1 while"},
        // Words after an O-word would be dropped: LinuxCNC refuses them, and so do we.
        {"words after endif", "o2 if [1]\nG0 X1\no2 endif G1 X5\n", 3, 10, "after O-word", "G1"},
        {"words after else", "o2 if [0]\nG0 X1\no2 else X5\nG0 X2\no2 endif\n", 3, 9, "after O-word", "X5"},
        {"words after a taken elseif", "o2 if [0]\no2 elseif [1] G0 X1\no2 endif\n", 2, 15, "after O-word", "G0"},
        {"words after do", "o1 do G0 X1\no1 while [0]\n", 1, 7, "after O-word", "G0"},
        {"words after endwhile", "#1 = 0\no1 while [#1 LT 1]\n#1 = 1\no1 endwhile X1\n", 4, 13, "after O-word", "X1"},
        {"words after repeat", "o1 repeat [2] G0 X1\no1 endrepeat\n", 1, 15, "after O-word", "G0"},
        {"words after endrepeat", "o1 repeat [1]\no1 endrepeat X1\n", 2, 14, "after O-word", "X1"},
        {"words after break", "o1 repeat [2]\no1 break X1\no1 endrepeat\n", 2, 10, "after O-word", "X1"},
        {"words after sub", "o<s> sub X1\no<s> endsub\n", 1, 10, "after O-word", "X1"},
        {"words after endsub", "o<s> sub\no<s> endsub [2] X1\no<s> call\n", 2, 17, "after O-word", "X1"},
        {"division by zero", "#1 = [1 / 0]\n", 1, 9, "division by zero", "/ 0"},
        {"MOD by zero", "#1 = [5 MOD 0]\n", 1, 9, "MOD by zero", "MOD"},
        {"sqrt of negative", "#1 = SQRT[-1]\n", 1, 6, "domain", "SQRT"},
        {"unclosed bracket", "G1 X[1 + 2\n", 1, 5, "unclosed '['", "[1 + 2"},
        {"undefined named parameter", "G1 X#<nope>\n", 1, 5, "not defined", "#<nope>"},
        {"parameter out of range", "#99999 = 1\n", 1, 1, "out of range", "#99999"},
        {"assignment without =", "#1 5\n", 1, 1, "without '='", "#1"},
        {"truncated file", "%\nG0 X1\nG1 X2\n", 3, 1, "closing '%'", "G1 X2"},
        {"unknown G-code", "G7.7 X1\n", 1, 1, "unsupported G-code", "G7.7"},
        {"threading", "G33 Z-1 K1\n", 1, 1, "unsupported motion", "G33"},
        {"rotary axis", "G0 X1 A10\n", 1, 7, "rotary", "A10"},
        {"position beyond reach", "G1 X2000000000\n", 1, 0, "beyond the 1e9 mm", "G1 X2000000000"},
        {"inch position beyond reach", "G20 G1 Y-40000000\n", 1, 0, "beyond the 1e9 mm", "Y-40000000"},
        {"unknown word", "G0 X1 E5\n", 1, 7, "unknown word", "E5"},
        {"axis words without motion mode", "X10\n", 1, 1, "no motion mode", "X10"},
        {"cycle R below Z", "G0 Z5\nG81 X1 Y1 Z2 R-1\n", 2, 14, "R plane below", "R"},
        {"cycle without R", "G0 Z5\nG81 X1 Y1 Z-2\n", 2, 1, "without R", "G81"},
        {"cycle without Z", "G0 Z5\nG90 G81 X1 Y1 R2\n", 2, 5, "without Z depth", "G81"},
        // LinuxCNC's enhance_block: all axes missing with a motion code other than G0 and G1.
        {"cycle without axes", "G0 X0 Y0 Z10\nG81 R2\n", 2, 1, "all axes missing with motion code G81", "G81"},
        {"probe without axes", "G0 X0 Y0 Z10\nG91 G38.2 F10\n", 2, 5, "all axes missing with motion code G38.2", "G38.2"},
        {"dwell cycle without P", "G0 Z5\nG17 G82 X1 Y1 Z-2 R1\n", 2, 5, "G82/G89 without P", "G82"},
        {"peck without Q", "G0 Z5\nG83 X1 Y1 Z-2 R1\n", 2, 1, "without Q", "G83"},
        // LinuxCNC's convert_straight and convert_arc: under G93 each feed move's F is its time.
        {"inverse time G1 without F", "G0 X0 Y0 Z5\nG93\nG1 Z-1\n", 3, 1, "F word missing with inverse time G1 move",
         "G1"},
        {"inverse time modal G1 without F", "G0 X0 Y0 Z5\nG93 G1 Z-1 F2\nX4\n", 3, 1,
         "F word missing with inverse time G1 move", "X4"},
        {"inverse time arc without F", "G0 X0 Y0 Z5\nG93 G2 X10 I5 F1\nG3 X0 I-5\n", 3, 1,
         "F word missing with inverse time arc move", "G3"},
        // LinuxCNC's convert_cycle: no canned cycle under G93, given in the block or modal.
        {"inverse time cycle", "G0 X0 Y0 Z5\nG93 G81 X1 Y1 Z-2 R1 F1\n", 2, 5,
         "cannot use inverse time feed with canned cycles", "G81"},
        {"inverse time modal cycle", "G0 X0 Y0 Z5\nG81 X1 Y1 Z-2 R1 F100\nG93\nX3\n", 4, 1,
         "cannot use inverse time feed with canned cycles: give G94 before G81", "X3"},
        {"G10 without L", "G90 G10 P1 X5\n", 1, 5, "G10 without L", "G10"},
        {"G53 in G91", "G91 G53 G0 X5\n", 1, 5, "G53 in incremental mode", "G53"},
        {"negative feed rate", "G0 X0 Y0 Z0\nG1 X5 F-100\n", 2, 7, "negative feed rate F", "F-100"},
        {"negative feed rate from an expression", "G1 X5 F[2 - 3]\n", 1, 7, "negative feed rate F", "F[2"},
        {"M98 without P", "G0 X1 M98\nM30\n", 1, 7, "M98 without P", "M98"},
        {"cycle bottom beyond reach", "G0 Z5\nG81 X1 Y1 Z-2000000000 R1\n", 2, 11, "beyond the 1e9 mm", "Z-2000000000"},
        {"too many pecks", "G0 Z10\nG83 X1 Y1 Z-2000 R2 Q0.0001\n", 2, 21, "20020000 pecks, more than the 1000000",
         "Q0.0001"},
        {"call of undefined sub", "o<nowhere> call\n", 1, 1, "undefined subroutine", "o<nowhere>"},
        {"M98 to missing program", "M98 P42\nM30\n", 1, 5, "missing program", "P42"},
        {"return outside sub", "o9 return\n", 1, 1, "outside a subroutine", "o9 return"},
        {"Fanuc sub without M99", "M98 P5\nM30\nO5\nG0 X1\n", 4, 1, "missing M99", "G0 X1"},
        {"alarm", "#3000 = 1\n", 1, 1, "alarm", "#3000"},
        {"XY rotation", "G10 L2 P1 R30\n", 1, 11, "rotation", "R30"},
        {"bad G number", "G1.25 X1\n", 1, 1, "bad G-code", "G1.25"},
        {"N word late", "G0 N10 X1\n", 1, 4, "N word", "N10"},
        {"stray character", "G0 X1 @\n", 1, 7, "unexpected character", "@"},
        {"GOTO to missing line", "GOTO 99\n", 1, 0, "missing N99", ""},
        {"repeat count past the block limit", "o1 repeat [200000]\nG0 X1\no1 endrepeat\n", 1, 11,
         "exceeds the 100000 blocks", "[200000]"},
        {"M98 L past the block limit", "M98 P5 L200000\nM30\nO5\nG0 X1\nM99\n", 1, 8, "exceeds the 100000 blocks",
         "L200000"},
    };
    for (const Malformed& c : cases) {
        INFO(c.what << ": " << c.text);
        try {
            GcodeOptions options;
            options.startPosition = Vec3(0.0);
            options.maxBlocks = 100000;
            parseGcode(c.text, "bad.ngc", options);
            FAIL("no error");
        } catch (const ParseError& e) {
            INFO(e.what());
            CHECK(e.where().file == "bad.ngc");
            CHECK(e.where().line == c.line);
            if (c.column) CHECK(e.where().column == c.column);
            CHECK(e.message().find(c.message) != std::string::npos);
            CHECK(e.offending().find(c.offending) != std::string::npos);
            CHECK(std::string(e.what()).rfind("bad.ngc:" + std::to_string(c.line), 0) == 0);
        }
    }
    CHECK(sizeof(cases) / sizeof(cases[0]) >= 30);
}

TEST_CASE("gcode: expressions nested past the limit are a located error, not a stack overflow",
          "[path][gcode][errors]") {
    struct Deep {
        const char* what;
        std::string text;
        int column;  // where the level past the limit starts
    };
    const int limit = 500;
    const Deep cases[] = {
        {"unary signs", "G1 X" + std::string(40000, '-') + "1\n", 5 + limit},
        {"brackets", "G1 X" + std::string(20000, '[') + "1\n", 5 + limit},
        {"powers", "#1 = [1" + [] {
             std::string s;
             for (int k = 0; k < 100000; ++k) s += "**1";
             return s;
         }() + "]\n", 0},
        {"functions", "#1 = " + [] {
             std::string s;
             for (int k = 0; k < 5000; ++k) s += "ABS[";
             return s;
         }() + "1\n", 0},
    };
    for (const Deep& c : cases) {
        INFO(c.what);
        try {
            parseGcode(c.text, "deep.ngc");
            FAIL("no error");
        } catch (const ParseError& e) {
            CHECK(e.where().file == "deep.ngc");
            CHECK(e.where().line == 1);
            if (c.column) CHECK(e.where().column == c.column);
            CHECK(e.message().find("nested deeper than " + std::to_string(limit) + " levels") !=
                  std::string::npos);
        }
    }
    // At the limit, each bracket and the sign one level, the value is read as written.
    const std::string fine = "G1 X" + std::string(std::size_t(limit - 1), '[') + "-7" +
                             std::string(std::size_t(limit - 1), ']') + "\n";
    GcodeOptions options;
    options.startPosition = Vec3(0.0);
    const Program p = parseGcode(fine, "fine.ngc", options);
    REQUIRE_FALSE(p.path.moves.empty());
    CHECK(p.path.moves.back().end.x == Approx(-7.0));
}

TEST_CASE("gcode: loops that end are not taken for endless ones", "[path][gcode]") {
    // Each loop changes something its condition can read in every pass, though not always a
    // numbered parameter or by a plain assignment; each must run to its end.
    const struct {
        const char* what;
        const char* text;
        std::size_t moves;
    } loops[] = {
        {"position only", "o1 while [#5420 LT 5]\nG91 G1 X1\nG90\no1 endwhile\nM2\n", 5},
        {"there and back, and a counter", "#1 = 0\no1 while [#1 LT 4]\nG1 X10\nG1 X0\n#1 = [#1 + 1]\no1 endwhile\n", 8},
        {"a named global written by a sub", "#<_n> = 0\no<s> sub\n#<_n> = [#<_n> + 1]\no<s> endsub\n"
                                            "o1 while [#<_n> LT 3]\nG1 X#<_n>\no<s> call\no1 endwhile\n", 3},
        {"a work offset", "o1 while [#5221 LT 3]\nG10 L2 P1 X[#5221 + 1]\nG1 X0\no1 endwhile\n", 3},
        {"the tool", "o1 while [#5400 LT 3]\nT[#5400 + 1] M6\nG1 Z-#5400\no1 endwhile\n", 3},
        {"Fanuc GOTO with a counter", "#1 = 0\nN10 G1 X#1\n#1 = [#1 + 1]\nIF [#1 LT 4] GOTO 10\n", 4},
        {"a mode set after the move", "o1 while [#5420 LT 3]\nG1 X1\nG91\no1 endwhile\n", 3},
    };
    for (const auto& l : loops) {
        INFO(l.what);
        GcodeOptions options = linuxcnc();
        options.maxBlocks = 10000;
        Program p;
        REQUIRE_NOTHROW(p = parseGcode(l.text, "loop.ngc", options));
        CHECK(p.path.moves.size() == l.moves);
    }
}

TEST_CASE("gcode: arcs are split within the chord tolerance and end exactly", "[path][gcode]") {
    for (double tol : {0.001, 0.01, 0.1}) {
        GcodeOptions o;
        o.startPosition = Vec3(0.0);
        o.chordTolerance = tol;
        // Full circle, a half circle by R, and a helix of 2 turns.
        const Program p = runGcode("G0 X10 Y0 Z0\nG3 I-10 J0 X10 Y0\nG2 X-10 Y0 R10\nG17 G3 X-10 Y0 Z-4 I10 J0 P2\n", o);
        REQUIRE(p.path.moves.size() > 4);
        std::size_t full = 0;
        for (const Move& m : p.path.moves) {
            if (m.rapid) continue;
            // Every chord's ends are on the circle of radius 10 around the origin, and its middle
            // is within tol of it.
            const double r0 = std::hypot(m.start.x, m.start.y), r1 = std::hypot(m.end.x, m.end.y);
            CHECK(r0 == Approx(10).margin(1e-9));
            CHECK(r1 == Approx(10).margin(1e-9));
            const Vec3 mid = 0.5 * (m.start + m.end);
            CHECK(10.0 - std::hypot(mid.x, mid.y) <= tol + 1e-12);
            if (m.source.line == 2) ++full;
        }
        CHECK(full == std::size_t(std::ceil(2 * M_PI / (2 * std::acos(1 - tol / 10)) - 1e-12)));
        CHECK(near(p.path.moves.back().end, Vec3(-10, 0, -4)));
    }
}

TEST_CASE("gcode: an arc without axis words is a full circle, and centre words alone take the modal arc",
          "[path][gcode]") {
    // LinuxCNC's enhance_block lets G2/G3 go without axis words (the arc ends where it starts)
    // and gives a block of I/J/K alone to the active arc motion.
    const Program p = runGcode("G0 X10 Y0 Z-1\nG2 I-10\nG3 J5 P2\nI-10\n");
    for (int line : {2, 3, 4}) {
        Vec3 first(0.0), last(0.0);
        bool seen = false;
        std::size_t chords = 0;
        for (const Move& m : p.path.moves) {
            if (m.source.line != line) continue;
            if (!seen) first = m.start, seen = true;
            last = m.end;
            ++chords;
            CHECK(m.start.z == -1.0);
        }
        INFO("line " << line);
        REQUIRE(chords > 8);
        CHECK(near(first, Vec3(10, 0, -1)));
        CHECK(near(last, Vec3(10, 0, -1)));
    }
    // Line 2: a clockwise circle about the origin; line 3: two counter-clockwise turns about
    // (10, 5); line 4: the modal G3 of line 3 again, one counter-clockwise turn about the origin.
    const auto centreOf = [&](int line, const Vec3& c, double radius, int turnSign, double turns) {
        double swept = 0.0;
        for (const Move& m : p.path.moves) {
            if (m.source.line != line) continue;
            CHECK(std::hypot(m.start.x - c.x, m.start.y - c.y) == Approx(radius).margin(1e-9));
            const double a0 = std::atan2(m.start.y - c.y, m.start.x - c.x);
            const double a1 = std::atan2(m.end.y - c.y, m.end.x - c.x);
            double d = a1 - a0;
            if (d > M_PI) d -= 2 * M_PI;
            if (d < -M_PI) d += 2 * M_PI;
            swept += d;
        }
        CHECK(swept == Approx(turnSign * turns * 2 * M_PI).margin(1e-9));
    };
    centreOf(2, Vec3(0, 0, 0), 10.0, -1, 1.0);
    centreOf(3, Vec3(10, 5, 0), 5.0, +1, 2.0);
    centreOf(4, Vec3(0, 0, 0), 10.0, +1, 1.0);
    CHECK_FALSE(hasDiagnostic(p, "has no effect"));
}

TEST_CASE("gcode: G4 X is Fanuc's dwell time, not a move", "[path][gcode]") {
    const Program p = runGcode("G0 X0 Y0 Z5\nG1 Z-1\nG04 X1.5\nG4 P1 \nG1 Y3\n");
    for (const Move& m : p.path.moves) CHECK(m.end.x == 0.0);
    CHECK(p.path.moves.back().end.y == 3.0);
    CHECK(hasDiagnostic(p, "dwell G4 X: the time in seconds, as Fanuc writes it"));
}

TEST_CASE("gcode: an arc's end may be off its circle by LinuxCNC's tolerance of the program's units",
          "[path][gcode]") {
    // LinuxCNC's arc_data_ijk refuses only e > 0.0283 mm (G21) or 0.00283 inch (G20) when e is
    // also past 0.1 % of the radius: 0.025 mm of 10 mm and 0.0015 inch of 1 inch pass.
    const Program mm = runGcode("G21 G0 X0 Y0\nG2 X20.025 Y0 I10 J0\n");
    REQUIRE(mm.path.moves.size() > 2);
    CHECK(near(mm.path.moves.back().end, Vec3(20.025, 0, 0), 1e-12));
    const Program inch = runGcode("G20 G0 X0 Y0\nG2 X2.0015 Y0 I1 J0\n");
    REQUIRE(inch.path.moves.size() > 2);
    CHECK(near(inch.path.moves.back().end, Vec3(2.0015 * 25.4, 0, 0), 1e-9));
}

TEST_CASE("gcode: arcs in G18 and G19 turn the right way (UGS fixtures)", "[path][gcode]") {
    // G18 G2 from (-1.5,0,0) to (1.5,0,0) around the origin: clockwise seen from +Y, through
    // -Z, as UGS's own expansion beside the input shows.
    const Program a = runGcode("G18\nG0 X-1.5 Y0 Z0\nG2 X1.5 Z0 I1.5 K0\n");
    double zmax = -1, zmin2 = 1;
    for (const Move& m : a.path.moves) zmax = std::max(zmax, m.end.z), zmin2 = std::min(zmin2, m.end.z);
    CHECK(zmax == Approx(0).margin(1e-12));
    CHECK(zmin2 == Approx(-1.5).margin(1e-3));
    const Program b = runGcode("G19\nG0 Y-1.5 Z0 X0\nG3 Y1.5 Z0 J1.5 K0\n");
    double zmin = 1;
    for (const Move& m : b.path.moves) zmin = std::min(zmin, m.end.z);
    CHECK(zmin == Approx(-1.5).margin(1e-3));
}

TEST_CASE("gcode: units, distance modes, offsets and homes", "[path][gcode]") {
    const Program p = runGcode(
        "G20 G0 X1 Y2 Z3\n"          // inch
        "G21 G91 G0 X1\n"            // incremental mm
        "G90 G10 L2 P2 X100 Y0 Z0\n"
        "G55 G0 X0 Y0\n"             // machine X100
        "G92 X10\n"                  // here is X10 now
        "G0 X20\n"                   // machine X110
        "G92.1\n"
        "G53 G0 X5 Y5\n"             // machine coordinates
        "#5161 = 1 #5162 = 2 #5163 = 3\n"
        "G28 Z10\n"                  // via Z10 (program), then Z home = 3
        "M2\n");
    const auto& m = p.path.moves;
    REQUIRE(m.size() == 7);
    CHECK(near(m[0].end, Vec3(25.4, 50.8, 76.2)));
    CHECK(near(m[1].end, Vec3(26.4, 50.8, 76.2)));
    CHECK(near(m[2].end, Vec3(100, 0, 76.2)));
    CHECK(near(m[3].end, Vec3(110, 0, 76.2)));
    CHECK(near(m[4].end, Vec3(5, 5, 76.2)));
    CHECK(near(m[5].end, Vec3(5, 5, 10)));
    CHECK(near(m[6].end, Vec3(5, 5, 3)));
    for (const Move& mv : m) CHECK(mv.rapid);
    CHECK(m[3].source.line == 6);
}

TEST_CASE("gcode: G43.1's axis words set the offset and move nothing, G43.2's feed the modal motion",
          "[path][gcode]") {
    // LinuxCNC's enhance_block takes no motion for a block with G43.1 and no motion code, even
    // with G80 active; a G43.2 block's axis words go to the modal motion as any others do.
    const Program p = runGcode("G0 X0 Y0 Z10\nG1 X5 F100\nG43.1 Z5\nG1 X6\nG80\nG43.1 Z7\nG1 X7\nG43.2 Z-5\n");
    const auto& m = p.path.moves;
    REQUIRE(m.size() == 5);
    CHECK(near(m[1].end, Vec3(5, 0, 10)));
    CHECK(m[2].source.line == 4);
    CHECK(near(m[2].end, Vec3(6, 0, 10)));
    CHECK(near(m[3].end, Vec3(7, 0, 10)));
    CHECK(m[4].source.line == 8);
    CHECK(near(m[4].end, Vec3(7, 0, -5)));
}

TEST_CASE("gcode: stored positions and offsets keep their machine position across G20/G21", "[path][gcode]") {
    // LinuxCNC stores #5161.. (G28.1), #5211.. (G92) and #5221.. (G10 L2) in the machine's units
    // (mm here) and converts them to the program's units on use.
    const Program home = runGcode("G10 L2 P1 X0 Y0 Z0\nG21 G0 X10 Y0 Z5\nG28.1\nG0 X0 Y0 Z5\nG20\nG28\n");
    REQUIRE(home.path.moves.size() == 3);
    CHECK(near(home.path.moves[2].end, Vec3(10, 0, 5)));
    const Program g92 = runGcode("G21 G0 X0 Y0 Z0\nG0 X10\nG92 X0\nG92.2\nG20\nG92.3\nG0 X0\n");
    REQUIRE(g92.path.moves.size() == 3);
    CHECK(near(g92.path.moves[2].end, Vec3(10, 0, 0)));
    const Program g10 = runGcode("G20 G10 L2 P1 X1\nG21 G0 X#5221 Y0 Z0\n");
    REQUIRE(g10.path.moves.size() == 1);
    CHECK(near(g10.path.moves[0].end, Vec3(50.8, 0, 0), 1e-12));
}

TEST_CASE("gcode: tools, warnings and their aggregation", "[path][gcode]") {
    std::string text = "T1 M6\nS1000 M3\n";
    for (int i = 0; i < 1000; ++i) text += "G1 X" + std::to_string(i) + " F100\n";
    text += "T2\nG0 Z5\nM6\nG0 Z6\nM5 M9 M88\nG4 P1\nG41 D1\nG1 X0\nG40\nM2\n";
    const Program p = runGcode(text);
    REQUIRE(p.path.toolChanges.size() == 2);
    CHECK(p.path.toolChanges[0].tool == 1);
    CHECK(p.path.toolChanges[1].tool == 2);
    CHECK(p.path.toolChanges[1].moveIndex == 1001);
    CHECK(p.path.moves[1000].tool == 1);
    CHECK(p.path.moves[1001].tool == 2);
    // One feed warning for 1000 F words, with the count, at the first one.
    int feed = 0;
    for (const Diagnostic& d : p.diagnostics)
        if (d.message.find("feed rate F") != std::string::npos) {
            ++feed;
            CHECK(d.message.find("1000 occurrences") != std::string::npos);
            CHECK(d.where.line == 3);
            CHECK(d.where.column == 7);  // "G1 X0 F100": the F word
        }
    CHECK(feed == 1);
    for (const char* w : {"spindle speed", "spindle M3", "coolant", "M88", "dwell", "cutter radius compensation"})
        CHECK(hasDiagnostic(p, w));
    for (const Diagnostic& d : p.diagnostics)
        if (d.message.find("spindle speed") != std::string::npos) CHECK(d.where.column == 1);  // "S1000 M3"
    // The feed mode's warning names the G word's column.
    const Program inverse = runGcode("G21 G93 G1 X1 F2\n");
    bool g93 = false;
    for (const Diagnostic& d : inverse.diagnostics)
        if (d.message.find("G93") != std::string::npos) {
            g93 = true;
            CHECK(d.where.column == 5);
        }
    CHECK(g93);
    // CAMotics: T alone changes the tool.
    GcodeOptions camotics;
    camotics.startPosition = Vec3(0.0);
    camotics.toolChangeOnT = true;
    const Program q = runGcode("T3 G0 X1\n", camotics);
    REQUIRE(q.path.toolChanges.size() == 1);
    CHECK(q.path.moves[0].tool == 3);
}

TEST_CASE("gcode: parameters, expressions and O-word flow", "[path][gcode]") {
    const Program p = runGcode(
        "#1 = 2 #2 = [#1 * 3]\n"  // #2 reads the old #1 (0): assignments happen after the line
        "#<_r> = [ATAN[1]/[1] + SQRT[16] ** 2 - 10 MOD 3]\n"  // 45 + 16 - 1
        "G0 X#1 Y#2 Z#<_r>\n"
        "o<twice> sub\n"
        "  G0 X[#1 * 2]\n"
        "o<twice> endsub\n"
        "o<twice> call [7]\n"
        "#3 = 0\n"
        "o10 while [#3 LT 3]\n"
        "  #3 = [#3 + 1]\n"
        "  o11 if [#3 EQ 2]\n"
        "    G0 Y-2\n"
        "  o11 elseif [#3 EQ 3]\n"
        "    G0 Y-3\n"
        "  o11 else\n"
        "    G0 Y-1\n"
        "  o11 endif\n"
        "o10 endwhile\n"
        "o12 repeat [2]\n"
        "  G91\n  G0 Z1\n  G90\n"
        "o12 endrepeat\n"
        "G0 X#1\n"  // #1 restored after the call
        "M2\n");
    const auto& m = p.path.moves;
    REQUIRE(m.size() == 8);
    CHECK(near(m[0].end, Vec3(2, 0, 60)));
    CHECK(m[1].end.x == Approx(14));
    CHECK(m[2].end.y == Approx(-1));
    CHECK(m[3].end.y == Approx(-2));
    CHECK(m[4].end.y == Approx(-3));
    CHECK(m[6].end.z == Approx(62));
    CHECK(m[7].end.x == Approx(2));
}

TEST_CASE("gcode: G68.2 tilts coordinates and, after G53.1, the tool axis", "[path][gcode]") {
    const Program p = runGcode("G68.2 X10 Y0 Z0 Q121 I0 J90 K0\nG53.1\nG0 X0 Y0 Z5\nG69\nG0 X0 Y0 Z5\n");
    REQUIRE(p.path.moves.size() == 2);
    // Rotation about Y by 90 degrees: the plane's +Z is the part's +X.
    CHECK(near(p.path.moves[0].axis, Vec3(1, 0, 0), 1e-12));
    CHECK(near(p.path.moves[0].end, Vec3(15, 0, 0), 1e-12));
    CHECK(near(p.path.moves[1].axis, Vec3(0, 0, 1)));
    CHECK(near(p.path.moves[1].end, Vec3(0, 0, 5)));
}

TEST_CASE("gcode: G69 cancels the tilted plane and keeps the coordinate system", "[path][gcode]") {
    // LinuxCNC's G69 (work_plane_cancel in interp_workplane.cc) clears only the plane: G55 and
    // #5220 stay as they were.
    const Program p = runGcode("G10 L2 P2 X100\nG55\nG0 X0 Y0 Z10\nG68.2 X0 Y0 Z0 I0 J0 K0\nG69\nG0 X0 Y0 Z10\n"
                          "G0 X1\nG0 X#5220\n");
    const auto& m = p.path.moves;
    REQUIRE(m.size() == 4);
    CHECK(near(m[0].end, Vec3(100, 0, 10)));
    CHECK(near(m[1].end, Vec3(100, 0, 10)));
    CHECK(near(m[2].end, Vec3(101, 0, 10)));
    CHECK(near(m[3].end, Vec3(102, 0, 10)));
}

TEST_CASE("gcode: canned cycles G73 G83 G85 G89 and G99", "[path][gcode]") {
    const Program p = runGcode("G0 X0 Y0 Z10\nG99 G83 X1 Y1 Z-3 R2 Q2\nG85 X2 Z-1 R2\nG80\nG98 G73 X3 Z-1 R1 Q0.5\nG89 X4 Z-1 R1 P1\nM2\n");
    const auto& m = p.path.moves;
    REQUIRE(m.size() > 10);
    double zmin = 0;
    for (const Move& mv : m) zmin = std::min(zmin, mv.end.z);
    CHECK(zmin == Approx(-3));
    CHECK(m.back().end.z == Approx(2));  // G98: back to the level where this cycle began
    CHECK(hasDiagnostic(p, "dwell"));
}

TEST_CASE("gcode: after a G99 hole the next block travels at the R plane", "[path][gcode]") {
    // LinuxCNC's CYCLE_MACRO traverses to a block's first hole at the level the block starts
    // from (current_cc) when it is above R: after a G99 hole that is R itself, not the level
    // the series began at; G98 then climbs back to that level (old_cc).
    const Program p = runGcode("G17 G99\nG0 X0 Y0 Z10\nG81 X0 Y0 Z-5 R2\nX20\nG98 X40\nG80\nM2\n");
    const std::vector<Vec3> expected = {{0, 0, 10}, {0, 0, 10}, {0, 0, 2},   {0, 0, -5},  {0, 0, 2},
                                        {20, 0, 2}, {20, 0, -5}, {20, 0, 2}, {40, 0, 10}, {40, 0, 2},
                                        {40, 0, -5}, {40, 0, 10}};
    const auto& m = p.path.moves;
    REQUIRE(m.size() == expected.size());
    for (std::size_t k = 0; k < m.size(); ++k) {
        INFO("move " << k);
        CHECK(near(m[k].end, expected[k]));
    }
    CHECK(m[5].source.line == 4);
    CHECK(m[5].rapid);
    CHECK_FALSE(m[6].rapid);
}

TEST_CASE("gcode: inverse time needs F on each feed move until G94 ends it", "[path][gcode]") {
    const Program p = runGcode("G0 X0 Y0 Z5\nG93 G1 Z-1 F2\nG2 X10 I5 F1\nG0 Z5\nG94\nG1 Z-1\nM2\n");
    CHECK(p.path.moves.size() > 4);
    CHECK(p.path.moves.back().end.z == -1.0);
}

TEST_CASE("gcode: a rotary word that turns nothing is a warning without --machine, not dropped silently",
          "[path][gcode]") {
    const Program p = runGcode("G0 X0 Y0 Z20 A0\nG1 Z-8 F100\nG1 X5 C0\nM2\n");
    CHECK(p.path.moves.size() == 3);
    std::vector<std::pair<int, int>> at;
    for (const Diagnostic& d : p.diagnostics)
        if (d.message.find("turns nothing and is ignored") != std::string::npos) {
            CHECK(d.message.find("--machine") != std::string::npos);
            CHECK(d.message.find(d.where.line == 1 ? "'A0'" : "'C0'") != std::string::npos);
            at.emplace_back(d.where.line, d.where.column);
        }
    // Counted as one warning, at the first word: line 1, column 14.
    CHECK(at == std::vector<std::pair<int, int>>{{1, 14}});
}

TEST_CASE("gcode: a file of subroutines alone names each one it never calls", "[path][gcode]") {
    const std::string subs = "(pockets)\no<pocket> sub\nG1 X#1 F100\no<pocket> endsub\n"
                             "o<slot> sub\nG1 Y#1 F100\no<slot> endsub\n";
    const Program alone = runGcode(subs + "M2\n");
    CHECK(alone.path.moves.empty());
    std::vector<std::pair<std::string, int>> named;
    for (const Diagnostic& d : alone.diagnostics)
        if (d.message.find("never called") != std::string::npos) {
            CHECK(d.where.file == "test.ngc");
            named.emplace_back(d.message.substr(0, d.message.find('>') + 1), d.where.line);
        }
    CHECK(named == std::vector<std::pair<std::string, int>>{{"subroutine o<pocket>", 2}, {"subroutine o<slot>", 5}});
    // A program that moves is not told of the subroutines it leaves unused, nor of those it calls.
    const Program moving = runGcode(subs + "G0 X1 Y2 Z3\nM2\n");
    CHECK(moving.path.moves.size() == 1);
    CHECK_FALSE(hasDiagnostic(moving, "never called"));
    const Program called = runGcode("o<pocket> sub\nG1 X#1 F100\no<pocket> endsub\nG0 X0 Y0 Z5\no<pocket> call [4]\nM2\n");
    CHECK(called.path.moves.size() == 2);
    CHECK_FALSE(hasDiagnostic(called, "never called"));
    // A called subroutine that makes no moves is not one left uncalled.
    CHECK_FALSE(hasDiagnostic(runGcode("o<none> sub\n#1 = 2\no<none> endsub\no<none> call\nM2\n"), "never called"));
}

TEST_CASE("gcode: a feed move at a zero feed rate is one warning, G94 and G95 reset the feed rate",
          "[path][gcode]") {
    const std::string zeroFeed = "feed move with a zero feed rate";
    auto warnings = [&](const Program& p) {
        std::vector<std::pair<int, int>> at;
        for (const Diagnostic& d : p.diagnostics)
            if (d.message.find(zeroFeed) != std::string::npos) at.emplace_back(d.where.line, d.where.column);
        return at;
    };
    using At = std::vector<std::pair<int, int>>;
    // No F yet: the G1, the modal G1 and the arc are three such moves, told once, at the first.
    const Program none = runGcode("G0 X0 Y0 Z5\nG1 Z-1\nX10\nG2 X20 I5\n");
    CHECK(warnings(none) == At{{2, 1}});
    CHECK(hasDiagnostic(none, "(3 occurrences, first shown)"));
    CHECK(none.path.moves.size() > 3);  // the moves are simulated as programmed
    CHECK(warnings(runGcode("G0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\nG2 X20 I5\n")).empty());
    // LinuxCNC's convert_feed_mode: G94 and G95 set the feed rate to 0; an F in the same block
    // comes after the mode and holds.
    CHECK(warnings(runGcode("G1 X1 F100\nG94\nX2 Y1\n")) == At{{3, 1}});
    CHECK(warnings(runGcode("G1 X1 F100\nG95\nG1 X2\n")) == At{{3, 1}});
    CHECK(warnings(runGcode("G1 X1 F100\nG94 F200\nG1 X2\n")).empty());
    CHECK(warnings(runGcode("G1 X1 F0\n")) == At{{1, 1}});
    // A canned cycle feeds too; a rapid does not; in G93 each feed move carries its own F.
    CHECK(warnings(runGcode("G0 X0 Y0 Z5\nG81 X1 Z-1 R1\n")) == At{{2, 1}});
    CHECK(warnings(runGcode("G0 X1 Y1 Z1\nG93 G1 X2 F2\n")).empty());
}

