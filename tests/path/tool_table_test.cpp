// Tests of the LinuxCNC tool table reader: the words, comments and the errors' places.
#include <catch2/catch.hpp>

#include <fstream>
#include <string>

#include "dexelmill/error.h"
#include "dexelmill/path/tool_table.h"
#include "testdata.h"

using namespace dexelmill;
using namespace dexelmill::test;
using Catch::Matchers::Contains;

namespace {

/// The error parseToolTable gives for `text`, with its place: "file:line:col: error: ...".
std::string errorOf(const std::string& text) {
    try {
        parseToolTable(text, "t.tbl");
    } catch (const ParseError& e) {
        return e.where().str() + ": " + e.message();
    }
    return "<no error>";
}

}  // namespace

TEST_CASE("tool table: words in any order and case, comments, blank lines", "[path][tooltable]") {
    const std::string text =
        "T1 P1 Z0.5 D0.0625;first tool\n"
        "\n"
        "   ; a line that is only a comment\n"
        "p7 t12 d+6.35 z-1 x0 y0.25 ; wear \r\n"
        "T3 P3 Z+30 D10 I45 Q2\n"
        "T32 P32 D0.0;last tool";  // no line end at the end, as LinuxCNC writes some tables
    const std::vector<ToolTableEntry> t = parseToolTable(text, "t.tbl");
    REQUIRE(t.size() == 4);
    CHECK(t[0].number == 1);
    CHECK(t[0].diameter == 0.0625);
    CHECK(t[0].comment == "first tool");
    CHECK(t[0].where.str() == "t.tbl:1:1");
    CHECK(t[0].offsets.empty());  // Z is the tool length, P the pocket
    CHECK(t[1].number == 12);
    CHECK(t[1].diameter == 6.35);
    CHECK(t[1].where.str() == "t.tbl:4:4");
    CHECK(t[1].offsets == "Y");  // X is given as 0
    CHECK(t[1].comment == "wear");
    CHECK(t[2].latheWords == "I, Q");
    CHECK(t[3].number == 32);
    CHECK(t[3].diameter == 0.0);
    CHECK(t[3].comment == "last tool");
    CHECK(parseToolTable("T4 P4\n", "t.tbl").at(0).diameter == std::nullopt);
    CHECK(parseToolTable("", "t.tbl").empty());
}

TEST_CASE("tool table: a wrong word is an error at its line and column", "[path][tooltable][errors]") {
    CHECK_THAT(errorOf("T1 P1 D6\nT2 P2 R3\n"), Contains("t.tbl:2:7: a tool table has no word 'R'"));
    CHECK_THAT(errorOf("T1 P1 D\n"), Contains("t.tbl:1:7: the tool table's D word needs a number"));
    CHECK_THAT(errorOf("T1 P1 Dx\n"), Contains("t.tbl:1:7: the tool table's D word needs a number"));
    CHECK_THAT(errorOf("T1 P1 D6mm\n"), Contains("t.tbl:1:7: the tool table's D word needs a number"));
    CHECK_THAT(errorOf("T1.5 P1 D6\n"), Contains("t.tbl:1:1: the tool table's T must be a whole number"));
    CHECK_THAT(errorOf("T-1 P1 D6\n"), Contains("t.tbl:1:1: the tool table's T must be a whole number"));
    CHECK_THAT(errorOf("T1 P1e3 D6\n"), Contains("t.tbl:1:4: the tool table's P word needs a number"));
    CHECK_THAT(errorOf("T1 P1 D6 D7\n"), Contains("t.tbl:1:10: the tool table gives D twice on one line"));
    CHECK_THAT(errorOf("T1 P1 D-6\n"), Contains("t.tbl:1:7: the tool table's diameter D must not be negative"));
    CHECK_THAT(errorOf("P1 D6 ;no number\n"), Contains("t.tbl:1:1: this tool table line has no tool number (T)"));
    CHECK_THAT(errorOf("T1 P1 D6\nT2 P2 D3\n T1 P3 D4\n"),
               Contains("t.tbl:3:2: the tool table gives T1 again (first on line 1)"));
}

TEST_CASE("tool table: LinuxCNC's own tables read", "[path][tooltable]") {
    if (!haveSharedData()) return;
    const std::vector<ToolTableEntry> inch = readToolTable(sharedData() + "/linuxcnc/cam-nisley/test.tbl");
    REQUIRE(inch.size() == 5);
    CHECK(inch[0].number == 1);
    CHECK(inch[0].diameter == 0.0625);
    CHECK(inch[4].number == 32);
    const std::vector<ToolTableEntry> mm = readToolTable(sharedData() + "/linuxcnc/5axis-xyzac/xyzac-trt.tbl");
    REQUIRE(mm.size() >= 10);
    CHECK(mm[1].number == 2);
    CHECK(mm[1].diameter == 8.0);
    CHECK_THROWS_WITH(readToolTable("no/such.tbl"), Contains("'no/such.tbl'"));
}
