// The info command as a user runs it: what it names of a program's tools, what it prints of a
// level set, and that it prints nothing before an error.
#include <catch2/catch.hpp>

#include <string>
#include <utility>

#include "support/cli_run.h"

using Catch::Matchers::Contains;
using dexelmill::testing::Cli;
using dexelmill::testing::Run;

TEST_CASE("info prints a VDB's source with its control bytes escaped", "[cli][errors]") {
    // The source is the program's name, stored in the file: a damaged or crafted file may hold an
    // escape sequence there, which printed raw would drive the terminal.
    const Cli cli("vdb_source");
    cli.file("a\x1b[31mb.ngc", "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\nG0 Z5\n");
    REQUIRE(cli("simulate 'a\x1b[31mb.ngc' --stock box:-5,-5,-3,15,5,0 --tool flat:d=2 --resolution 0.5 "
                "--vdb part.vdb -q")
                .code == 0);
    const Run info = cli("info part.vdb");
    CHECK(info.code == 0);
    CHECK_THAT(info.out, Contains("a\\x1b[31mb.ngc"));
    CHECK(info.out.find('\x1b') == std::string::npos);
}

TEST_CASE("info names every tool a program calls, and which need a --tool", "[cli][info]") {
    const Cli cli("info_tools");
    // No tool table: neither number has a cutter.
    // What info prints of `text`, written as `name`.
    const auto info = [&cli](const std::string& name, const std::string& text) {
        cli.file(name, text);
        const Run r = cli("info " + name);
        CHECK(r.code == 0);
        return r.out;
    };
    CHECK_THAT(info("two.ngc", "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F100\nT2 M6\nG1 X5\nM30\n"),
               Contains("tool           T1: no cutter defined; give one with --tool 1=SPEC\n"
                        "tool           T2: no cutter defined; give one with --tool 2=SPEC\n"));
    // Moves before any tool change are made with none.
    CHECK_THAT(info("none.ngc", "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F100\n"),
               Contains("tool           T0 (no tool selected): no cutter defined; give one with --tool SPEC\n"));
    // A tool changed to that makes no move needs no cutter, as simulate takes it.
    CHECK_THAT(info("t5.ngc", "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F100\nT5 M6\nM30\n"),
               Contains("T1: no cutter defined") && !Contains("T5"));
    // A project defines tool 1; its program calls 2 as well, which simulate cuts with tool 1.
    const std::string project =
        info("p.camotics", R"({"tools": {"1": {"units": "metric", "shape": "cylindrical", "length": 20, "diameter": 6}},
                              "files": ["two.ngc"]})");
    CHECK_THAT(project, Contains("tool           T1: flat D6") &&
                            Contains("tool           T2: not defined; simulate cuts with the only tool defined, T1 "
                                     "(flat D6"));
    CHECK_THAT(project, Contains("unless given --tool 2=SPEC\n") && !Contains("no cutter"));
    const Run simulated = cli("simulate p.camotics -o p.obj");
    CHECK(simulated.code == 0);
    CHECK_THAT(simulated.err, Contains("using the only tool defined, T1"));
    // An APT program defines every tool it cuts with (CUTTER/), so none lacks one.
    CHECK_THAT(info("p.apt", "CUTTER/6\nFROM/0,0,5\nGOTO/5,0,-1\nFINI\n"),
               Contains("tool           T1: ") && !Contains("no cutter"));
}

TEST_CASE("info prints nothing before an error in its inputs", "[cli][info][errors]") {
    const Cli cli("info_errors");
    cli.file("ok.ngc", "G21\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F100\n");
    cli.file("bad.json", R"({"axes": [{"letter": "A", "on": "table", "direction": [0, 0, 0]}]})");
    cli.file("bad.ngc", "G21\nG0 X0 Y0 Z5\nG1 X1.2.3 F100\n");
    cli.file("lost.camotics", R"({"files": ["nowhere.ngc"]})");
    for (const auto& [args, says] : {std::pair<const char*, const char*>{"info ok.ngc --machine bad.json", "bad.json"},
                                     {"info lost.camotics --machine bad.json", "bad.json"},
                                     {"info bad.ngc", "bad.ngc:3:"},
                                     {"info lost.camotics", "nowhere.ngc"},
                                     {"info nowhere.vdb", "nowhere.vdb"}}) {
        INFO(args);
        const Run r = cli(args);
        CHECK(r.code == 1);
        CHECK_THAT(r.err, Contains(says));
        CHECK(r.out.empty());
    }
}

TEST_CASE("info refuses a program's options for a level set, rather than ignore them", "[cli][info][errors]") {
    const Cli cli("info_vdb_options");
    for (const auto& [args, option] : {std::pair<const char*, const char*>{"info part.vdb --machine xyzac-trt", "--machine"},
                                       {"info part.vdb --start 0,0,10", "--start"}}) {
        INFO(args);
        const Run r = cli(args);
        CHECK(r.code == 2);
        CHECK_THAT(r.err, Contains(std::string(option) + " applies to a program; 'part.vdb' is a level set"));
        CHECK(r.out.empty());
    }
}
