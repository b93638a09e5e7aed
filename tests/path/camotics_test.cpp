// Tests of the CAMotics project reader and readProgram.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "dexelmill/error.h"
#include "dexelmill/path/camotics.h"
#include "testdata.h"

using namespace dexelmill;

TEST_CASE("camotics: every project of the shared testdata runs unchanged", "[path][camotics]") {
    if (!test::haveSharedData()) return;
    const std::string base = test::sharedData() + "/camotics/";
    for (const char* name : {"bear/bear", "botomata_bottom/botomata_bottom", "heart/heart",
                             "scorpion/scorpion", "slant_test/slant_test", "vcarve/vcarve"}) {
        INFO(name);
        const std::string file = base + name + ".camotics";
        const Project project = readCamoticsProject(file);
        CHECK_FALSE(project.tools.empty());
        CHECK_FALSE(project.files.empty());
        CHECK(project.resolution > 0);
        const Program p = readProgram(file);
        CHECK(p.path.moves.size() > 10);
        CHECK(p.path.files.size() == project.files.size());
    }
}

TEST_CASE("camotics: tools, units and workpiece are read", "[path][camotics]") {
    if (!test::haveSharedData()) return;
    const std::string base = test::sharedData() + "/camotics/";
    const Project bear = readCamoticsProject(base + "bear/bear.camotics");
    REQUIRE(bear.tools.count(1) == 1);
    CHECK(bear.tools.at(1).cuttingRadius() == Approx(0.125 * 25.4 / 2));  // imperial ball 1/8"
    CHECK_FALSE(bear.workpiece.automatic);
    CHECK(bear.workpiece.bounds.hi.x == Approx(80));
    CHECK(bear.workpiece.bounds.lo.z == Approx(-20));
    CHECK(bear.files.at(0) == base + "bear/bear.nc");

    const Project heart = readCamoticsProject(base + "heart/heart.camotics");
    CHECK(heart.files.size() == 2);
    CHECK(heart.workpiece.marginPercent == Approx(5));

    const Project vcarve = readCamoticsProject(base + "vcarve/vcarve.camotics");
    CHECK(vcarve.tools.at(1).cuttingRadius() == Approx(1.0));  // conical D2 L2
    CHECK(vcarve.tools.at(1).radiusAt(0.0) == Approx(0.0).margin(1e-9));

    // slant_test: a snub-nose taper, automatic bounds with a 1% margin; the program calls T3,
    // which the project does not define.
    const Project slant = readCamoticsProject(base + "slant_test/slant_test.camotics");
    CHECK(slant.tools.at(1).radiusAt(0.0) == Approx(1.0));
    CHECK(slant.workpiece.automatic);
    const Program p = runProject(slant);
    bool warned = false;
    for (const Diagnostic& d : p.diagnostics)
        warned = warned || d.message.find("tool 3") != std::string::npos;
    CHECK(warned);
    const Box box = automaticWorkpieceBounds(p, slant.workpiece.marginPercent);
    CHECK(box.lo.x == Approx(slant.workpiece.bounds.lo.x).margin(1e-6));
    CHECK(box.lo.y == Approx(slant.workpiece.bounds.lo.y).margin(1e-6));
    CHECK(box.lo.z == Approx(slant.workpiece.bounds.lo.z).margin(1e-6));
    CHECK(box.hi.x == Approx(slant.workpiece.bounds.hi.x).margin(1e-6));
    CHECK(box.hi.y == Approx(slant.workpiece.bounds.hi.y).margin(1e-6));
    CHECK(box.hi.z == Approx(slant.workpiece.bounds.hi.z).margin(1e-6));
}

TEST_CASE("camotics: comments are allowed, errors carry their place", "[path][camotics]") {
    const std::string text = R"({
      // a comment
      "units": "imperial",
      "tools": {"2": {"units": "metric", "shape": "cylindrical", "length": 10, "diameter": 3}},
      "workpiece": {"automatic": false, "margin": 0, "bounds": {"min": [0, 0, -1], "max": [1, 1, 0]}},
      "files": ["a.nc"]
    })";
    const Project p = parseCamoticsProject(text, "p.camotics", "/tmp");
    CHECK_FALSE(p.metric);
    CHECK(p.tools.at(2).cuttingRadius() == Approx(1.5));
    CHECK(p.workpiece.bounds.hi.x == Approx(25.4));
    CHECK(p.files.at(0) == "/tmp/a.nc");

    try {
        parseCamoticsProject("{\n  \"units\": \"metric\",\n  \"tools\": ,\n}", "bad.camotics", "");
        FAIL("expected an error");
    } catch (const ParseError& e) {
        CHECK(e.where().line == 3);
        CHECK(e.where().column > 0);
    }
    CHECK_THROWS_AS(parseCamoticsProject(R"({"tools": {"1": {"shape": "hexagon", "length": 1, "diameter": 1}}})", "x", ""), ParseError);
    CHECK_THROWS_AS(parseCamoticsProject(R"({"tools": {"1": {"shape": "ballnose", "length": 1, "diameter": -1}}})", "x", ""), ParseError);
    CHECK_THROWS_AS(parseCamoticsProject(R"({"workpiece": {"bounds": {"min": [0, 0], "max": [1, 1, 1]}}})", "x", ""), ParseError);
}

TEST_CASE("readProgram: the bundled samples of every kind read", "[path][camotics]") {
    const std::string dir = std::string(DEXELMILL_TEST_DATA) + "/path/";
    const Program g = readProgram(dir + "sample.ngc");
    CHECK(g.path.moves.size() > 20);
    const Program a = readProgram(dir + "sample.apt");
    CHECK(a.tools.count(1) == 1);
    CHECK(a.path.moves.size() > 10);
    const Program c = readProgram(dir + "sample.camotics");
    CHECK(c.tools.size() == 3);
    CHECK(c.path.moves.size() == g.path.moves.size());
    CHECK(detectProgramKind("x.unknown", "PARTNO/X\nGOTO/1,2,3\n") == ProgramKind::Apt);
    CHECK(detectProgramKind("x.unknown", "G0 X1\n") == ProgramKind::Gcode);
}

TEST_CASE("camotics: a number JSON cannot hold is a ParseError, not a library exception", "[path][errors]") {
    // Found by the libFuzzer smoke run: nlohmann::json throws out_of_range for it.
    const std::string text = R"({"resolution": 5555555E5555555555555555555555555})";
    CHECK_THROWS_AS(parseCamoticsProject(text, "big.camotics", "."), ParseError);
    CHECK_THROWS_WITH(parseCamoticsProject(text, "big.camotics", "."), Catch::Matchers::Contains("big.camotics"));
}
