// Tests of the tools a job cuts with: the command line's, the program's, a tool table's, stand-ins.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "dexelmill/error.h"
#include "dexelmill/tool/builders.h"
#include "job/detail/tools.h"
#include "support/scratch.h"

using namespace dexelmill;
using Catch::Matchers::Contains;

namespace {

/// A program whose moves use the tools `numbers` in turn, move k from line k + 1 of "p.ngc".
Program usingTools(std::initializer_list<int> numbers) {
    Program p;
    p.path.files.push_back("p.ngc");
    int line = 1;
    for (int n : numbers) {
        Move m;
        m.start = Vec3(0.0), m.end = Vec3(1, 0, 0), m.tool = n, m.source = SourceRef{0, line++};
        p.path.moves.push_back(m);
    }
    return p;
}

/// `text` as the tool table t.tbl in a fresh folder; its path.
std::string table(const std::string& name, const std::string& text) {
    const std::filesystem::path p = testing::scratchFolder("dexelmill_tools_", name) / "t.tbl";
    std::ofstream(p) << text;
    return p.string();
}

/// The messages of `p`'s diagnostics, each "where: message".
std::vector<std::string> messages(const Program& p) {
    std::vector<std::string> out;
    for (const Diagnostic& d : p.diagnostics) out.push_back(d.where.str() + ": " + d.message);
    return out;
}

}  // namespace

TEST_CASE("tools: a tool table serves the numbers the program and --tool leave undefined", "[job][tools]") {
    SimulateOptions o;
    o.toolTable = table("serves", "T1 P1 D6 ;six\nT2 P2 D8 X0.5 Y1\nT3 P3 D10 Q2\nT9 P9 D4\n");
    o.tools.emplace(2, bullNoseEndMill(8, 1));
    Program p = usingTools({1, 2, 3});
    p.tools.emplace(3, ballEndMill(10));
    const ToolTable tools = detail::resolveTools(o, p);
    // T1 from the table, a flat end of its diameter; T2 from --tool; T3 the program's own.
    CHECK(tools.at(1).radiusAt(0.0) == 3.0);
    CHECK(tools.at(1).radiusAt(20.0) == 3.0);
    CHECK(tools.at(2).radiusAt(0.0) == 3.0);  // the bull nose's flat bottom: 4 - 1
    CHECK(tools.at(3).radiusAt(0.0) == 0.0);  // the ball's tip
    CHECK(tools.count(9) == 0);               // unused, so not built
    // Only the tool taken from the table is warned of, at its line: its offsets and lathe word
    // belong to tools the table does not serve.
    const std::vector<std::string> said = messages(p);
    REQUIRE(said.size() == 1);
    CHECK_THAT(said[0], Contains("t.tbl:1:1: T1 is cut as a flat D6"));
    CHECK_THAT(said[0], Contains("a tool table gives no shape; --tool 1=SPEC gives it"));
}

TEST_CASE("tools: a tool table's offsets and lathe words are warned of, and inches scaled", "[job][tools]") {
    SimulateOptions o;
    o.toolTable = table("inch", "T1 P1 D0.25 X0.5 Y1 Q2\nT2 P2 D0.5 U0.1\n");
    o.toolTableUnit = 25.4;
    Program p = usingTools({1, 2});
    const ToolTable tools = detail::resolveTools(o, p);
    CHECK(tools.at(1).radiusAt(0.0) == Approx(3.175));
    CHECK(tools.at(2).radiusAt(0.0) == Approx(6.35));
    const std::vector<std::string> said = messages(p);
    REQUIRE(said.size() == 5);
    CHECK_THAT(said[1], Contains("t.tbl:1:1: T1's offsets X, Y are not simulated"));
    CHECK_THAT(said[2], Contains("t.tbl:1:1: T1's lathe word Q is not simulated"));
    CHECK_THAT(said[4], Contains("t.tbl:2:1: T2's offset U is not simulated"));
}

TEST_CASE("tools: a tool table's entry that cannot cut is an error at its line", "[job][tools][errors]") {
    const auto errorFor = [](int tool, const std::string& text) {
        SimulateOptions o;
        o.toolTable = table("errors", text);
        Program p = usingTools({tool});
        try {
            detail::resolveTools(o, p);
        } catch (const ParseError& e) {
            return e.where().str() + ": " + e.message();
        }
        return std::string("<no error>");
    };
    CHECK_THAT(errorFor(4, "T1 P1 D6\nT4 P4 D0\n"), Contains("t.tbl:2:1: T4 has diameter 0 in the tool table"));
    CHECK_THAT(errorFor(5, "T5 P5 Z10\n"), Contains("t.tbl:1:1: T5 has no diameter (D) in the tool table"));
    CHECK_THAT(errorFor(6, "T6 P6 D20001\n"), Contains("t.tbl:1:1: T6 in the tool table: flat end mill: diameter d"));
    // An entry no move uses is never built, and a number the table lacks is the usual error.
    CHECK_THAT(errorFor(7, "T4 P4 D0\n"), Contains("p.ngc:1: the program uses tool T7"));
    // A wrong word stops the job wherever it is.
    CHECK_THAT(errorFor(1, "T1 P1 D6\nT2 P2 D6 K1\n"), Contains("t.tbl:2:10: a tool table has no word 'K'"));
}

TEST_CASE("tools: a tool table that serves no tool is warned of", "[job][tools]") {
    SimulateOptions o;
    o.toolTable = table("unused", "T1 P1 D6\n");
    o.tools.emplace(1, flatEndMill(3));
    Program p = usingTools({1});
    detail::resolveTools(o, p);
    const std::vector<std::string> said = messages(p);
    REQUIRE(said.size() == 1);  // --tool 1 replaces nothing the program defines: no note of that
    CHECK_THAT(said[0], Contains("--tool-table " + o.toolTable + " is not used"));
}
