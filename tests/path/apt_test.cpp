// Tests of the APT CL reader.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <optional>
#include <string>

#include "dexelmill/error.h"
#include "dexelmill/path/apt.h"
#include "support/gcode_run.h"
#include "testdata.h"

using namespace dexelmill;

namespace {

using testing::hasDiagnostic;

/// The error parseApt raises on `text` read as `file`; none (and a failed check) when it reads it.
std::optional<ParseError> errorOf(const std::string& text, const std::string& file) {
    try {
        parseApt(text, file);
    } catch (const ParseError& e) {
        return e;
    }
    FAIL_CHECK("no error");
    return std::nullopt;
}

}  // namespace

TEST_CASE("apt: every APT program of the shared testdata parses", "[path][apt]") {
    if (!test::haveSharedData()) return;
    namespace fs = std::filesystem;
    int count = 0;
    for (const auto& entry : fs::recursive_directory_iterator(test::sharedData())) {
        if (entry.path().extension() != ".apt") continue;
        INFO(entry.path().string());
        Program p;
        REQUIRE_NOTHROW(p = readApt(entry.path().string()));
        CHECK(p.path.moves.size() > 50);
        CHECK_FALSE(p.tools.empty());
        for (const Move& m : p.path.moves) {
            REQUIRE(p.tools.count(m.tool) == 1);
            REQUIRE(std::abs(glm::length(m.axis) - 1.0) < 1e-9);
        }
        CHECK(hasDiagnostic(p, "FEDRAT"));
        ++count;
    }
    CHECK(count == 4);
}

TEST_CASE("apt: motion, CIRCLE, cycles and frames", "[path][apt]") {
    const Program p = parseApt(
        "UNITS/MM\nCUTTER/10,0,5,0,0,0,50\nLOAD/TOOL,3\nFEDRAT/100,MMPM\n"
        "FROM/0,0,10\nRAPID\nGOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10\nGOTO/0,10,0\n"
        "CYCLE/DRILL,FEDTO,5,MMPM,50,RAPTO,2,RTRCTO,10\nGOTO/20,20,0\nCYCLE/OFF\n"
        "CUTCOM/LEFT\nGODLTA/0,0,5\nFINI\n",
        "t.apt");
    REQUIRE(p.tools.count(3) == 1);
    const auto& m = p.path.moves;
    REQUIRE(m.size() > 6);
    CHECK(m[0].rapid);
    CHECK(m[0].tool == 3);
    // The quarter circle turns counter-clockwise about +Z: through x, y > 0.
    for (std::size_t k = 1; m[k].source.line == 9; ++k) {
        CHECK(std::hypot(m[k].end.x, m[k].end.y) == Approx(10));
        CHECK(m[k].end.x >= -1e-9);
        CHECK(m[k].end.y >= -1e-9);
    }
    double zmin = 1e9;
    for (const Move& mv : m) zmin = std::min(zmin, mv.end.z);
    CHECK(zmin == Approx(-5));
    CHECK(m.back().end.z == Approx(15));
    CHECK(hasDiagnostic(p, "CUTCOM"));
    CHECK(hasDiagnostic(p, "FEDRAT"));

    // A rotated CSYS without TRNTYP/WORLD maps local coordinates; its z column is the axis.
    const Program q = parseApt("CUTTER/6\nCSYS/0,0,1,5,0,1,0,0,-1,0,0,0\nFROM/0,0,0\nGOTO/0,0,10\n", "q.apt");
    REQUIRE(q.path.moves.size() == 1);
    CHECK(q.path.moves[0].end.x == Approx(15));
    CHECK(q.path.moves[0].axis.x == Approx(1));
}

TEST_CASE("apt: a GOTO with a new i,j,k turns the axis during its move; non-unit vectors are reported",
          "[path][apt]") {
    const Program p = parseApt("MULTAX\nCUTTER/10\nGOTO/0,0,30,0,0,1\nGOTO/10,0,30,0,0,1\n"
                               "GOTO/90,0,5,0.5,0,0.8660254\nGOTO/80,0,5\nGOTO/80,0,5,0,-0.173648,.984808\n"
                               "GOTO/70,0,5,0,0,2\nFINI\n",
                               "t.apt");
    const auto& m = p.path.moves;
    // The first GOTO only places the tool.
    REQUIRE(m.size() == 5);
    CHECK_FALSE(m[0].turns());
    REQUIRE(m[1].turns());
    CHECK(*m[1].startAxis == Vec3(0, 0, 1));
    CHECK(m[1].axis.x == Approx(0.5));
    CHECK(m[1].axis.z == Approx(std::sqrt(0.75)));
    CHECK_FALSE(m[2].turns());
    CHECK(m[2].axis == m[1].axis);
    // A turn where the tip stays: the rotation alone, as a move of zero length.
    REQUIRE(m[3].turns());
    CHECK(m[3].feed() == Vec3(0.0));
    CHECK(*m[3].startAxis == m[1].axis);
    REQUIRE(m[4].turns());
    CHECK(m[4].axis == Vec3(0, 0, 1));
    // Printed to 6 digits, (0, -0.173648, .984808) is a unit vector; (0, 0, 2) is not, and says so.
    int nonUnit = 0;
    for (const Diagnostic& d : p.diagnostics) {
        if (d.message.find("not 1") == std::string::npos) continue;
        ++nonUnit;
        CHECK(d.where.line == 8);
        CHECK(d.where.column == 13);
        CHECK(d.message.find("length 2") != std::string::npos);
    }
    CHECK(nonUnit == 1);
    // FROM's axis and CIRCLE's are read alike: normalised, with a warning at the vector.
    const struct {
        const char* text;
        int line, column;
        const char* message;
    } others[] = {
        {"MULTAX\nCUTTER/10\nFROM/5,0,0,0,0,2\nGOTO/0,5,0\nFINI\n", 3, 12, "tool axis i,j,k of length 2"},
        {"MULTAX\nCUTTER/10\nFROM/5,0,0\nCIRCLE/0,0,0,0,0,3,5\nGOTO/0,5,0\nFINI\n", 4, 14, "CIRCLE axis i,j,k of length 3"},
        // A vector whose length overflows a double is still a direction.
        {"MULTAX\nCUTTER/10\nFROM/5,0,0\nGOTO/6,0,0,0,0,1e300\nFINI\n", 4, 12, "tool axis i,j,k of length 1e+300"},
    };
    for (const auto& o : others) {
        INFO(o.text);
        const Program q = parseApt(o.text, "q.apt");
        REQUIRE_FALSE(q.path.moves.empty());
        CHECK(glm::length(q.path.moves.back().axis - Vec3(0, 0, 1)) < 1e-15);
        int warned = 0;
        for (const Diagnostic& d : q.diagnostics) {
            if (d.message.find("not 1") == std::string::npos) continue;
            ++warned;
            CHECK(d.where.line == o.line);
            CHECK(d.where.column == o.column);
            CHECK(d.message.find(o.message) != std::string::npos);
        }
        CHECK(warned == 1);
    }
}

TEST_CASE("apt: malformed programs give a parse error with file:line:col and the text",
          "[path][apt][errors]") {
    struct Case {
        const char* text;
        int line;
        const char* message;
        const char* offending;
    };
    const Case cases[] = {
        {"GOTO/1,2,3\n", 1, "missing CUTTER", "GOTO"},
        {"CUTTER/6\nGOTO/1,2\n", 2, "GOTO needs", "GOTO/1,2"},
        {"CUTTER/6\nFROM/0,0,5\nGOTO/10,0,-1\nGOTO/1E200,0,-1\n", 4, "beyond the 1e9 mm", "GOTO"},
        {"CUTTER/6\nFROM/0,-2E9,5\n", 2, "beyond the 1e9 mm", "FROM"},
        {"CUTTER/6\nFROM/0,0,5\nGODLTA/0,0,-3E9\n", 3, "beyond the 1e9 mm", "GODLTA"},
        {"CUTTER/6\nGOTO/1,2,3x\n", 2, "bad number", "3X"},
        {"CUTTER/-6\n", 1, "positive", "-6"},
        {"CUTTER/6,-1\n", 1, "corner radius must not be negative", "-1"},
        {"CUTTER/6,3.5\n", 1, "exceeds half the diameter", "3.5"},
        {"CUTTER/6\nFROM/5,0,0\nCIRCLE/0,0,0,0,0,1,0\nGOTO/0,5,0\n", 3, "CIRCLE radius must be positive", "0"},
        {"CUTTER/6\nFROM/1,0,0\nCIRCLE/0,0,0,0,0,1\nGOTO/3,3,0\n", 4, "not on the circle", "GOTO"},
        {"CUTTER/6\nFROM/1,0,0\nCIRCLE/0,0,0,0,0,1\n", 3, "truncated", ""},
        // An arc starts where the tool is: before any position it has no start.
        {"CUTTER/6\nCIRCLE/0,0,0,0,0,1\nGOTO/10,0,0\nGOTO/20,0,0\n", 2, "CIRCLE before any position", "CIRCLE"},
        {"CUTTER/6\nGOTO/1,2,$\n", 2, "truncated", "GOTO"},
        {"CUTTER/6\nCYCLE/TAPX,FEDTO,1\n", 2, "unsupported CYCLE", "TAPX"},
        {"CUTTER/6\nCYCLE/DRILL,RAPTO,1\n", 2, "without FEDTO", "CYCLE"},
        {"CUTTER/6\nCSYS/1,0,0\n", 2, "12 numbers", "CSYS"},
        {"UNITS/FURLONGS\n", 1, "unknown units", "FURLONGS"},
        {"CUTTER/6,0,3,0,0,0,-5\nLOAD/TOOL,1\n", 1, "height must not be negative", "-5"},
        {"CUTTER/6,2,5,2,0,0,10\nLOAD/TOOL,1\n", 1, "no real tool", ""},
        // The size a tool may have applies in mm: 400 inches are 10160 mm.
        {"CUTTER/1E155\nLOAD/TOOL,1\n", 1, "diameter d = 1e+155 mm is beyond the 10000 mm", ""},
        {"UNITS/INCHES\nCUTTER/400\nLOAD/TOOL,1\n", 2, "diameter d = 10160 mm is beyond the 10000 mm", ""},
        // APT's CUTTER has 1, 2 or 7 numbers: the 5- and 6-number forms lack the last ones.
        {"CUTTER/10,0,5,0,0\nGOTO/0,0,0\nGOTO/1,0,0\n", 1, "lacks beta,h", "CUTTER"},
        {"CUTTER/10,0,5,0,0,0\nGOTO/0,0,0\nGOTO/1,0,0\n", 1, "lacks h", "CUTTER"},
        {"CUTTER/10,0,5,0,0,0,30,1\n", 1, "1, 2 or 7 numbers", "CUTTER"},
        {"MULTAX\nCUTTER/6\nGOTO/1,2,3,0,0,1\nGOTO/4,5,6,0,0,0\n", 4, "tool axis i,j,k of zero length", "GOTO"},
        {"CUTTER/6\nFROM/0,0,5,0,0,0\n", 2, "tool axis i,j,k of zero length", "FROM"},
        {"CUTTER/6\nFROM/5,0,0\nCIRCLE/0,0,0,0,0,0,5\nGOTO/0,5,0\n", 3, "CIRCLE axis i,j,k of zero length", "CIRCLE"},
    };
    for (const Case& c : cases) {
        INFO(c.text);
        const std::optional<ParseError> e = errorOf(c.text, "bad.apt");
        if (!e) continue;
        INFO(e->what());
        CHECK(e->where().file == "bad.apt");
        CHECK(e->where().line == c.line);
        CHECK(e->message().find(c.message) != std::string::npos);
        CHECK(e->offending().find(c.offending) != std::string::npos);
    }
}

TEST_CASE("apt: a stock size stated as CAMWorks' INSERT/Stock Size", "[path][apt]") {
    const Program p = parseApt("INSERT/Stock Size X350. Y150. Z10.5\nCUTTER/6\nFROM/0,0,10\nGOTO/1,0,10\n", "s.apt");
    REQUIRE(p.statedStock);
    CHECK(p.statedStock->size == Vec3(350.0, 150.0, 10.5));
    CHECK(p.statedStock->where.file == "s.apt");
    CHECK(p.statedStock->where.line == 1);
    CHECK_FALSE(hasDiagnostic(p, "INSERT text ignored"));
    // Any case and spacing; inch programs in mm; the last statement wins.
    const Program q = parseApt("UNITS/INCHES\nINSERT/stock size x1 y2. z 0.5\nINSERT/STOCK SIZE X2 Y3 Z1\n"
                               "CUTTER/0.25\nFROM/0,0,1\nGOTO/1,0,1\n", "q.apt");
    REQUIRE(q.statedStock);
    CHECK(q.statedStock->size.x == Approx(50.8));
    CHECK(q.statedStock->size.y == Approx(76.2));
    CHECK(q.statedStock->size.z == Approx(25.4));
    CHECK(q.statedStock->where.line == 3);
    // Other text stays an ignored INSERT; a size that is not positive is an error at its line.
    for (const char* text : {"INSERT/Stock Size X350. Y150.\n", "INSERT/Stock Size X1 Y2 Z3 mm\n", "INSERT/Stock\n"}) {
        const Program r = parseApt(std::string(text) + "CUTTER/6\nFROM/0,0,10\nGOTO/1,0,10\n", "r.apt");
        CHECK_FALSE(r.statedStock);
        CHECK(hasDiagnostic(r, "INSERT text ignored"));
    }
    CHECK_THROWS_WITH(parseApt("INSERT/Stock Size X0 Y2 Z3\n", "z.apt"), Catch::Contains("z.apt:1") && Catch::Contains("positive"));
}

TEST_CASE("apt: a CUTTER applies to the moves after it, with or without LOAD/TOOL", "[path][apt]") {
    // CUTTER/2 with no LOAD/TOOL after the D10 has cut: the move after it is made with a D2, as a
    // tool change, and the moves before keep the D10.
    const Program p = parseApt("CUTTER/10\nGOTO/0,0,10\nGOTO/10,0,10\nCUTTER/2\nGOTO/20,0,10\nFINI\n", "c.apt");
    REQUIRE(p.path.moves.size() == 2);
    const int first = p.path.moves[0].tool, second = p.path.moves[1].tool;
    CHECK(first == 1);
    CHECK(second == 2);  // numbered after the largest number the program names
    REQUIRE(p.tools.count(first) == 1);
    REQUIRE(p.tools.count(second) == 1);
    CHECK(p.tools.at(first).cuttingRadius() == Approx(5));
    CHECK(p.tools.at(second).cuttingRadius() == Approx(1));
    REQUIRE(p.path.toolChanges.size() == 2);
    CHECK(p.path.toolChanges[1].moveIndex == 1);
    CHECK(p.path.toolChanges[1].tool == second);
    // A CUTTER that states the tool in use again changes nothing.
    const Program same = parseApt("CUTTER/10\nGOTO/0,0,10\nGOTO/10,0,10\nCUTTER/10\nGOTO/20,0,10\n", "s.apt");
    CHECK(same.tools.size() == 1);
    CHECK(same.path.toolChanges.size() == 1);
    // CUTTER then LOAD/TOOL (the usual order), LOAD/TOOL then CUTTER, and LOADTL/n, the Fusion
    // and NCL posts' word for loading tool n: one change per tool, each with its own cutter.
    for (const char* text : {"CUTTER/10\nLOAD/TOOL,3\nGOTO/0,0,10\nGOTO/10,0,10\nCUTTER/2\nLOAD/TOOL,4\nGOTO/20,0,10\n",
                             "LOAD/TOOL,3\nCUTTER/10\nGOTO/0,0,10\nGOTO/10,0,10\nLOAD/TOOL,4\nCUTTER/2\nGOTO/20,0,10\n",
                             "LOADTL/3,IN,0,LENGTH,40\nCUTTER/10\nGOTO/0,0,10\nGOTO/10,0,10\nLOADTL/4\nCUTTER/2\n"
                             "GOTO/20,0,10\n"}) {
        INFO(text);
        const Program q = parseApt(text, "q.apt");
        REQUIRE(q.path.moves.size() == 2);
        CHECK(q.path.moves[0].tool == 3);
        CHECK(q.path.moves[1].tool == 4);
        REQUIRE(q.tools.size() == 2);
        CHECK(q.tools.at(3).cuttingRadius() == Approx(5));
        CHECK(q.tools.at(4).cuttingRadius() == Approx(1));
        CHECK(q.path.toolChanges.size() == 2);
        CHECK_FALSE(hasDiagnostic(q, "statement LOADTL ignored"));
    }
}

TEST_CASE("apt: a tool number described anew keeps the moves made before with their cutter", "[path][apt]") {
    // Tool 1 is a D10 for the first move and a D2 from the second CUTTER on: the later moves get
    // an entry of their own, numbered after the largest number the program names (1).
    const Program p = parseApt(
        "CUTTER/10\nLOAD/TOOL,1\nGOTO/0,0,10\nGOTO/10,0,10\nCUTTER/2\nLOAD/TOOL,1\nGOTO/20,0,10\nFINI\n", "r.apt");
    REQUIRE(p.path.moves.size() == 2);
    CHECK(p.path.moves[0].tool == 1);
    CHECK(p.path.moves[1].tool == 2);
    REQUIRE(p.tools.size() == 2);
    CHECK(p.tools.at(1).cuttingRadius() == Approx(5));
    CHECK(p.tools.at(2).cuttingRadius() == Approx(1));
    REQUIRE(p.path.toolChanges.size() == 2);
    CHECK(p.path.toolChanges[1].tool == 2);
    CHECK(hasDiagnostic(p, "tool T2"));
    // A cutting length stated anew after the tool has cut is a new description too.
    const Program f = parseApt("CUTTER/10\nLOAD/TOOL,1\nCSI_SET_FLUTE_LENGTH/20\nGOTO/0,0,10\nGOTO/10,0,10\n"
                               "CUTTER/10\nLOAD/TOOL,1\nCSI_SET_FLUTE_LENGTH/30\nGOTO/20,0,10\n",
                               "f.apt");
    REQUIRE(f.path.moves.size() == 2);
    REQUIRE(f.tools.size() == 2);
    CHECK(f.tools.at(f.path.moves[0].tool).cuttingLength() == Approx(20));
    CHECK(f.tools.at(f.path.moves[1].tool).cuttingLength() == Approx(30));
    // Loading a tool again with the CUTTER it had (as CAMWorks writes it) is no new tool.
    const Program q = parseApt("CUTTER/5\nLOAD/TOOL,13\nGOTO/0,0,10\nGOTO/10,0,10\nCUTTER/6\nLOAD/TOOL,15\n"
                               "GOTO/20,0,10\nCUTTER/5\nLOAD/TOOL,13\nGOTO/30,0,10\n",
                               "q.apt");
    REQUIRE(q.path.moves.size() == 3);
    CHECK(q.tools.size() == 2);
    CHECK(q.path.moves[2].tool == 13);
    CHECK(q.path.toolChanges.size() == 3);
}

TEST_CASE("apt: an arc between GOTOs whose tool axes differ turns the axis over all its chords", "[path][apt]") {
    // A half circle of radius 10 about +z from (10, 0, 0) to (-10, 0, 0), while the axis turns
    // from +z to (0.6, 0, 0.8), theta = atan2(0.6, 0.8) in all. At the share t of the arc the
    // axis is (sin(t theta), 0, cos(t theta)), so each chord turns by theta / n.
    const Program p = parseApt("MULTAX\nCUTTER/10\nGOTO/10,0,0,0,0,1\nCIRCLE/0,0,0,0,0,1,10\nGOTO/-10,0,0,0.6,0,0.8\n",
                               "a.apt");
    const auto& m = p.path.moves;
    REQUIRE(m.size() >= 4);
    const double theta = std::atan2(0.6, 0.8);
    const double n = double(m.size());
    for (std::size_t i = 0; i < m.size(); ++i) {
        INFO(i);
        REQUIRE(m[i].turns());
        const double t0 = double(i) / n, t1 = double(i + 1) / n;
        CHECK(m[i].startAxis->x == Approx(std::sin(t0 * theta)).margin(1e-12));
        CHECK(m[i].startAxis->y == Approx(0).margin(1e-12));
        CHECK(m[i].startAxis->z == Approx(std::cos(t0 * theta)).margin(1e-12));
        CHECK(m[i].axis.x == Approx(std::sin(t1 * theta)).margin(1e-12));
        CHECK(m[i].axis.y == Approx(0).margin(1e-12));
        CHECK(m[i].axis.z == Approx(std::cos(t1 * theta)).margin(1e-12));
        CHECK(std::hypot(m[i].end.x, m[i].end.y) == Approx(10));
    }
    CHECK(glm::length(m.back().axis - Vec3(0.6, 0, 0.8)) < 1e-15);
    // Opposite axes have no one great circle: an error at the GOTO that ends the arc.
    CHECK_THROWS_WITH(parseApt("MULTAX\nCUTTER/10\nGOTO/10,0,0,0,0,1\nCIRCLE/0,0,0,0,0,1,10\nGOTO/-10,0,0,0,0,-1\n", "o.apt"),
                      Catch::Contains("o.apt:5:1") && Catch::Contains("opposite"));
    // So have a GOTO's: the same error, at the GOTO's line and column, from the reader that info
    // and simulate share.
    CHECK_THROWS_WITH(parseApt("MULTAX\nCUTTER/10\nFROM/0,0,20,0,0,1\nGOTO/0,0,-8,0,0,1\n  GOTO/5,0,-8,0,0,-1\n", "g.apt"),
                      Catch::Contains("g.apt:5:3") && Catch::Contains("turns 180 degrees") &&
                          Catch::Contains("opposite"));
}

TEST_CASE("apt: a '$' that ends PPRINT, INSERT or PARTNO text is text, not a continuation", "[path][apt]") {
    // In either of APT's forms: with a slash, and with a blank (`PARTNO text`).
    for (const std::string word : {"PPRINT/", "INSERT/", "PARTNO/", "PPRINT ", "PARTNO ", "REMARK "}) {
        INFO(word);
        const Program p = parseApt("CUTTER/10\nGOTO/0,0,10\n" + word + "COST IN $\nGOTO/10,0,10\nGOTO/10,10,10\nFINI\n",
                                   "t.apt");
        REQUIRE(p.path.moves.size() == 2);
        CHECK(p.path.moves[0].end == Vec3(10, 0, 10));
        CHECK(p.path.moves[1].end == Vec3(10, 10, 10));
        const std::string major = word.substr(0, 6);
        CHECK(hasDiagnostic(p, major + " text ignored"));
    }
    // Other statements still continue on the next line.
    const Program q = parseApt("CUTTER/10\nGOTO/0,0,10\nGOTO/10,$\n0,10\n", "q.apt");
    REQUIRE(q.path.moves.size() == 1);
    CHECK(q.path.moves[0].end == Vec3(10, 0, 10));
}

TEST_CASE("apt: MULTAX/OFF brings back the axis of a GOTO without i,j,k, and takes no i,j,k", "[path][apt]") {
    const Program p = parseApt("UNITS/MM\nCUTTER/10\nMULTAX/ON\nGOTO/0,0,10,0,0.6,0.8\nGOTO/10,0,10,0,0.6,0.8\n"
                               "MULTAX/OFF\nGOTO/10,0,20\nGOTO/30,0,20\nFINI\n",
                               "m.apt");
    const auto& m = p.path.moves;
    REQUIRE(m.size() == 3);
    CHECK(glm::length(m[0].axis - Vec3(0, 0.6, 0.8)) < 1e-15);
    // The first move after MULTAX/OFF turns back to +z, as a GOTO with new i,j,k turns.
    REQUIRE(m[1].turns());
    CHECK(glm::length(*m[1].startAxis - Vec3(0, 0.6, 0.8)) < 1e-15);
    CHECK(m[1].axis == Vec3(0, 0, 1));
    CHECK_FALSE(m[2].turns());
    CHECK(m[2].axis == Vec3(0, 0, 1));
    // With a CSYS, the default axis is its z column, (1, 0, 0) here.
    const Program c = parseApt("MULTAX\nCUTTER/6\nCSYS/0,0,1,5,0,1,0,0,-1,0,0,0\nFROM/0,0,0\nGOTO/0,0,10,0,1,0\n"
                               "MULTAX/OFF\nGOTO/0,0,20\n",
                               "c.apt");
    REQUIRE(c.path.moves.size() == 2);
    CHECK(glm::length(c.path.moves[0].axis - Vec3(0, 1, 0)) < 1e-15);
    CHECK(glm::length(c.path.moves[1].axis - Vec3(1, 0, 0)) < 1e-15);
    // Under MULTAX/OFF a point is x,y,z: six numbers are an error at the fourth, not an axis.
    const struct {
        const char* text;
        int line, column;
    } refused[] = {
        {"CUTTER/10\nMULTAX/OFF\nGOTO/0,0,10\nGOTO/10,0,10,0,0.6,0.8\n", 4, 14},
        {"MULTAX/OFF\nCUTTER/10\nFROM/0,0,10,0,0,1\n", 3, 13},
    };
    for (const auto& r : refused) {
        INFO(r.text);
        const std::optional<ParseError> e = errorOf(r.text, "off.apt");
        if (!e) continue;
        INFO(e->what());
        CHECK(e->where().line == r.line);
        CHECK(e->where().column == r.column);
        CHECK(e->message().find("MULTAX/OFF") != std::string::npos);
    }
}

TEST_CASE("apt: a FROM that puts the tool elsewhere after it has a place is reported", "[path][apt]") {
    // The tool is at (10, 0, 0) when FROM says (50, 0, 0): the 40 mm between are not simulated.
    const Program p = parseApt("CUTTER/10\nFROM/0,0,0\nGOTO/10,0,0\nFROM/50,0,0\nGOTO/60,0,0\nFINI\n", "f.apt");
    REQUIRE(p.path.moves.size() == 2);
    CHECK(p.path.moves[1].start == Vec3(50, 0, 0));
    int warned = 0;
    for (const Diagnostic& d : p.diagnostics) {
        if (d.message.find("not simulated") == std::string::npos) continue;
        ++warned;
        CHECK(d.where.line == 4);
        CHECK(d.where.column == 1);
        CHECK(d.message.find("(10, 0, 0)") != std::string::npos);
        CHECK(d.message.find("(50, 0, 0)") != std::string::npos);
    }
    CHECK(warned == 1);
    // The first FROM, and a FROM that states the place the tool is at, move nothing.
    const Program q = parseApt("CUTTER/10\nFROM/0,0,0\nGOTO/10,0,0\nFROM/10,0,0\nGOTO/20,0,0\n", "q.apt");
    CHECK_FALSE(hasDiagnostic(q, "not simulated"));
}

TEST_CASE("apt: a statement continued at the end of the file names the '$'", "[path][apt][errors]") {
    const struct {
        const char* text;
        int line, column;
    } cases[] = {
        {"CUTTER/6\nGOTO/1,2,$", 2, 10},
        {"CUTTER/6\nGOTO/1,$\n  2,$\n", 3, 5},
    };
    for (const auto& c : cases) {
        INFO(c.text);
        const std::optional<ParseError> e = errorOf(c.text, "eof.apt");
        if (!e) continue;
        INFO(e->what());
        CHECK(e->where().line == c.line);
        CHECK(e->where().column == c.column);
        CHECK(e->message().find("end of the file") != std::string::npos);
    }
}

TEST_CASE("apt: arguments a statement does not take are reported where they stand", "[path][apt]") {
    const Program p = parseApt("UNITS/MM\nCUTTER/10\nRAPID/100,200\nGOTO/0,0,10\nGOTO/10,0,10\nCYCLE/OFF,FOO\n"
                               "MULTAX/ON,X\nFINI/BAR\n",
                               "a.apt");
    const struct {
        const char* message;
        int line, column;
    } expected[] = {
        {"RAPID argument 100 ignored (2 occurrences", 3, 7},
        {"CYCLE/OFF argument FOO ignored", 6, 11},
        {"MULTAX argument X ignored", 7, 11},
        {"FINI argument BAR ignored", 8, 6},
    };
    for (const auto& e : expected) {
        INFO(e.message);
        int found = 0;
        for (const Diagnostic& d : p.diagnostics) {
            if (d.message.find(e.message) == std::string::npos) continue;
            ++found;
            CHECK(d.where.line == e.line);
            CHECK(d.where.column == e.column);
        }
        CHECK(found == 1);
    }
    // Two units cannot both hold: an error at the second.
    CHECK_THROWS_WITH(parseApt("UNITS/MM,INCHES\n", "u.apt"), Catch::Contains("u.apt:1:10") && Catch::Contains("one word"));
}

TEST_CASE("apt: LOAD/TOOL,0 after a CUTTER loads tool 0", "[path][apt]") {
    const Program p = parseApt("CUTTER/10\nLOAD/TOOL,0\nGOTO/0,0,10\nGOTO/10,0,10\nFINI\n", "z.apt");
    REQUIRE(p.path.moves.size() == 1);
    CHECK(p.path.moves[0].tool == 0);
    REQUIRE(p.tools.count(0) == 1);
    CHECK(p.tools.at(0).cuttingRadius() == Approx(5));
    REQUIRE(p.path.toolChanges.size() == 1);
    CHECK(p.path.toolChanges[0].tool == 0);
}

TEST_CASE("apt: two programs run in turn keep their own tools where they share a number", "[path][apt]") {
    // Each file loads its own CUTTER as tool 1: the first's moves are cut with its D10, the
    // second's with its D6 under a number neither file uses (2), and a note says so.
    Program p = parseApt("CUTTER/10\nLOAD/TOOL,1\nGOTO/0,0,10\nGOTO/10,0,10\nFINI\n", "a.apt");
    p.append(parseApt("CUTTER/6\nLOAD/TOOL,1\nGOTO/0,0,10\nGOTO/0,10,10\nFINI\n", "b.apt"));
    REQUIRE(p.path.moves.size() == 2);
    CHECK(p.path.moves[0].tool == 1);
    CHECK(p.path.moves[1].tool == 2);
    REQUIRE(p.tools.size() == 2);
    CHECK(p.tools.at(1).cuttingRadius() == Approx(5));
    CHECK(p.tools.at(2).cuttingRadius() == Approx(3));
    REQUIRE(p.path.toolChanges.size() == 2);
    CHECK(p.path.toolChanges[1].tool == 2);
    CHECK(hasDiagnostic(p, "its moves here are tool T2"));

    // The same CUTTER under the same number is one tool.
    Program same = parseApt("CUTTER/10\nLOAD/TOOL,1\nGOTO/0,0,10\nGOTO/10,0,10\nFINI\n", "a.apt");
    same.append(parseApt("CUTTER/10\nLOAD/TOOL,1\nGOTO/0,0,10\nGOTO/0,10,10\nFINI\n", "c.apt"));
    CHECK(same.tools.size() == 1);
    CHECK(same.path.moves[1].tool == 1);
}

namespace {

/// The one tool a CUTTER loaded as tool 1 makes, and the program's diagnostics.
Program cutterProgram(const std::string& cutter) {
    return parseApt(cutter + "\nLOAD/TOOL,1\nFROM/0,0,10\nGOTO/10,0,10\nFINI\n", "c.apt");
}

}  // namespace

TEST_CASE("apt: a note about a CUTTER names its own line, not the statement that takes it up", "[path][apt]") {
    const auto noteAt = [](const Program& p, const std::string& fragment) -> SourceLocation {
        for (const Diagnostic& d : p.diagnostics)
            if (d.message.find(fragment) != std::string::npos) return d.where;
        FAIL_CHECK("no note with '" << fragment << "'");
        return {};
    };
    // A CUTTER no LOAD/TOOL claims is tool 1 from the first GOTO (line 4) on; the note is about
    // the CUTTER of line 2.
    const Program p = parseApt("UNITS/MM\nCUTTER/3.96875,1.98438\nFROM/0,0,10\nGOTO/0,0,5\nGOTO/10,0,5\n", "c.apt");
    const SourceLocation claimed = noteAt(p, "CUTTER without LOAD/TOOL: taken as tool 1");
    CHECK(claimed.line == 2);
    CHECK(claimed.column == 1);
    CHECK(noteAt(p, "taken as that ball").line == 2);
    // Cutting lengths stated anew (lines 5 and 7) after the tool has cut make new tools; the moves
    // before each keep the CUTTER of line 1, not a CSI_SET_FLUTE_LENGTH.
    const Program f = parseApt("CUTTER/10\nLOAD/TOOL,1\nGOTO/0,0,10\nGOTO/10,0,10\nCSI_SET_FLUTE_LENGTH/30\n"
                               "GOTO/20,0,10\nCSI_SET_FLUTE_LENGTH/40\nGOTO/30,0,10\n",
                               "f.apt");
    REQUIRE(f.tools.size() == 3);
    CHECK(noteAt(f, "(its moves before keep the CUTTER of line 1): the moves from here are tool T2").line == 5);
    CHECK(noteAt(f, "(its moves before keep the CUTTER of line 1): the moves from here are tool T3").line == 7);
}

TEST_CASE("apt: a ball CUTTER printed to six digits or four decimals is the ball of its diameter, with a note",
          "[path][apt]") {
    // A 5/32 inch ball in mm: d = 3.96875, r = 1.984375, printed 1.98438. r - d/2 = 5e-6 mm.
    for (const char* cutter : {"CUTTER/3.96875,1.98438", "CUTTER/3.96875,1.98438,0,1.98438,0,0,50"}) {
        INFO(cutter);
        const Program p = cutterProgram(cutter);
        REQUIRE(p.tools.count(1) == 1);
        const Tool& t = p.tools.at(1);
        CHECK(t.cuttingRadius() == 3.96875 / 2);
        CHECK(t.radiusAt(0.0) == 0.0);
        CHECK(t.radiusAt(3.96875 / 2) == 3.96875 / 2);
        CHECK(hasDiagnostic(p, "r = 1.98438 mm"));
        CHECK(hasDiagnostic(p, "ball end mill of diameter 3.96875 mm (d/2 = 1.984375 mm)"));
    }
    CHECK(hasDiagnostic(cutterProgram("CUTTER/3.96875,1.98438,0,1.98438,0,0,50"), "e = 0 mm, f = 1.98438 mm"));
    // The same ball printed to four decimals in inches: d/2 = 0.07815 and r = 0.0781 inch are
    // each within half a unit of the fourth decimal of 5/64 = 0.078125.
    const Program inch = cutterProgram("UNITS/INCHES\nCUTTER/0.1563,0.0781");
    REQUIRE(inch.tools.count(1) == 1);
    CHECK(inch.tools.at(1).cuttingRadius() == Approx(0.1563 * 25.4 / 2));
    CHECK(inch.tools.at(1).radiusAt(0.0) == 0.0);
    // An exact ball needs no note; a corner radius short of d/2 by more than the digits is a bull nose.
    const Program exact = cutterProgram("CUTTER/6,3");
    CHECK(exact.tools.at(1).radiusAt(0.0) == 0.0);
    CHECK_FALSE(hasDiagnostic(exact, "ball end mill"));
    const Program bull = cutterProgram("CUTTER/6,2.999");
    CHECK(bull.tools.at(1).radiusAt(0.0) == Approx(0.001));
    CHECK_FALSE(hasDiagnostic(bull, "ball end mill"));
    // One past the digits is refused, and its message tells the two numbers apart.
    const std::optional<ParseError> e = errorOf("CUTTER/6,3.0002\nLOAD/TOOL,1\n", "r.apt");
    REQUIRE(e);
    CHECK_THAT(e->message(), Catch::Contains("corner radius 3.0002 exceeds half the diameter, 3"));
}

TEST_CASE("apt: a CUTTER whose d is not its corner's diameter beyond the printed digits is refused, naming both",
          "[path][apt][errors]") {
    // d/2 = 50.05 but e + r = 50: 0.05 mm, where six digits of each value allow 5e-4 mm.
    for (const auto& [cutter, says] :
         {std::pair<const char*, const char*>{"CUTTER/100.1,2,48,2,0,0,50", "d = 100.1 is not the diameter its corner makes, 2 (e + r cos(beta)) = 100"},
          {"CUTTER/10.02,2,3,2,0,0,50", "d = 10.02 is not the diameter its corner makes, 2 (e + r cos(beta)) = 10"},
          {"CUTTER/6.352,0.7937,2.3812,0.7937,0,0,50", "d = 6.352 is not the diameter its corner makes"}}) {
        INFO(cutter);
        const std::optional<ParseError> e = errorOf(std::string(cutter) + "\nLOAD/TOOL,1\n", "d.apt");
        REQUIRE(e);
        CHECK(e->where().line == 1);
        CHECK_THAT(e->message(), Catch::Contains("CUTTER describes no real tool") && Catch::Contains(says));
    }
    // A 1/4 inch bull nose with a 1/32 inch corner printed to four decimals, in mm (6.35, 0.79375,
    // 2.38125 rounded) and in inches: e + r misses d/2 by 1e-4 of the unit, within the digits.
    for (const char* cutter : {"CUTTER/6.35,0.7937,2.3812,0.7937,0,0,50", "UNITS/INCHES\nCUTTER/0.25,0.0313,0.0938,0.0313,0,0,2"}) {
        INFO(cutter);
        const Program p = cutterProgram(cutter);
        REQUIRE(p.tools.count(1) == 1);
    }
    CHECK(cutterProgram("CUTTER/6.35,0.7937,2.3812,0.7937,0,0,50").tools.at(1).cuttingRadius() == Approx(3.1749));
}
