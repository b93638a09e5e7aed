// Tests of the CAMotics project reader and readProgram.
#include <catch2/catch.hpp>

#include <cmath>
#include <iterator>
#include <map>
#include <optional>
#include <string>

#include "dexelmill/error.h"
#include "dexelmill/path/camotics.h"
#include "dexelmill/tool/builders.h"
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
    CHECK(bear.files.at(0).path == base + "bear/bear.nc");

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
    CHECK(p.files.at(0).path == "/tmp/a.nc");

    try {
        parseCamoticsProject("{\n  \"units\": \"metric\",\n  \"tools\": ,\n}", "bad.camotics", "");
        FAIL("expected an error");
    } catch (const ParseError& e) {
        CHECK(e.where().line == 3);
        CHECK(e.where().column > 0);
    }
    CHECK_THROWS_AS(parseCamoticsProject(R"({"tools": {"1": {"shape": "hexagon", "length": 1, "diameter": 1}}})", "x", ""), ParseError);
    // A key twice (the library keeps the last) and nesting past the readers' limit: located.
    CHECK_THROWS_WITH(parseCamoticsProject("{\n  \"units\": \"metric\",\n  \"units\": \"imperial\"\n}", "two.camotics", ""),
                      Catch::Contains("two.camotics:3:3: error: CAMotics project: the key \"units\" is given twice"));
    CHECK_THROWS_WITH(parseCamoticsProject("{\"files\": " + std::string(100000, '[') + std::string(100000, ']') + "}",
                                           "deep.camotics", ""),
                      Catch::Contains("deep.camotics:1:74: error") && Catch::Contains("nested deeper than 64"));
    CHECK_THROWS_AS(parseCamoticsProject(R"({"tools": {"1": {"shape": "ballnose", "length": 1, "diameter": -1}}})", "x", ""), ParseError);
    CHECK_THROWS_AS(parseCamoticsProject(R"({"workpiece": {"bounds": {"min": [0, 0], "max": [1, 1, 1]}}})", "x", ""), ParseError);
}

TEST_CASE("camotics: project units only choose how CAMotics shows lengths", "[path][camotics]") {
    // CAMotics keeps the workpiece and the resolution in mm (its window divides them by 25.4 to
    // show inches), its G-code starts in mm whatever the project's units, and only a tool's own
    // units scale the tool.
    const std::string text = R"({
      "units": "imperial", "resolution-mode": "manual", "resolution": 0.5,
      "tools": {"1": {"units": "imperial", "shape": "cylindrical", "length": 1, "diameter": 0.25},
                "2": {"shape": "cylindrical", "length": 10, "diameter": 3}},
      "workpiece": {"automatic": false, "bounds": {"min": [0, 0, -10], "max": [40, 30, 0]}},
      "files": ["a.nc"]
    })";
    const Project p = parseCamoticsProject(text, "p.camotics", "/d");
    CHECK_FALSE(p.metric);
    CHECK(p.resolution == 0.5);
    CHECK(p.workpiece.bounds.hi.x == 40.0);
    CHECK(p.workpiece.bounds.lo.z == -10.0);
    CHECK(p.tools.at(1).cuttingRadius() == Approx(0.125 * 25.4));
    CHECK(p.tools.at(2).cuttingRadius() == Approx(1.5));
    bool said = false;
    for (const Diagnostic& d : p.diagnostics) said = said || d.message.find("project units are imperial") != std::string::npos;
    CHECK(said);

    GcodeOptions o;
    const std::map<std::string, std::string> files = {{"/d/a.nc", "T1\nG0 X0 Y0 Z5\nG1 X20 F100\nG20\nG1 X1\n"}};
    o.files = [&files](const std::string& path) -> std::optional<std::string> {
        const auto it = files.find(path);
        if (it == files.end()) return std::nullopt;
        return it->second;
    };
    const Program program = runProject(p, o);
    REQUIRE(program.path.moves.size() == 2);
    CHECK(program.path.moves[0].end.x == Approx(20.0));  // mm until G20
    CHECK(program.path.moves[1].end.x == Approx(25.4));
}

TEST_CASE("camotics: the resolution of a mode is CAMotics' own number", "[path][camotics]") {
    // The numbers CAMotics saved beside each mode in the shared projects, with their workpieces.
    CHECK(projectResolution(ResolutionMode::High, Box{Vec3(0, 0, -20), Vec3(80, 80, 0)}) ==
          Approx(0.294723).epsilon(2e-6));  // bear
    CHECK(projectResolution(ResolutionMode::High, Box{Vec3(-40, -40, -12.7), Vec3(40, 40, 0)}) ==
          Approx(0.253321).epsilon(2e-6));  // heart
    CHECK(projectResolution(ResolutionMode::Medium, Box{Vec3(-45.7195, -45.7195, -20), Vec3(45.7195, 147.3195, 0)}) ==
          Approx(1.121903).epsilon(2e-6));  // botomata_bottom
    CHECK(projectResolution(ResolutionMode::Medium, Box{Vec3(-2.89442, 0.476477, -0.5), Vec3(13.5167, 5.56491, 0.25)}) ==
          Approx(0.06304).epsilon(2e-5));  // vcarve
    // Low and very high by their cell counts: 1e5 and 1e7 cells of a 1000 mm^3 block.
    const Box block{Vec3(0.0), Vec3(10, 10, 10)};
    CHECK(projectResolution(ResolutionMode::Low, block) == Approx(std::cbrt(1e-2)));
    CHECK(projectResolution(ResolutionMode::VeryHigh, block) == Approx(std::cbrt(1e-4)));

    auto mode = [](const char* m) {
        return parseCamoticsProject(std::string(R"({"resolution-mode": ")") + m + "\"}", "p.camotics", "")
            .resolutionMode;
    };
    CHECK(parseCamoticsProject("{}", "p.camotics", "").resolutionMode == ResolutionMode::Medium);
    CHECK(mode("manual") == ResolutionMode::Manual);
    CHECK(mode("High") == ResolutionMode::High);
    CHECK(mode("very_high") == ResolutionMode::VeryHigh);
    CHECK_THROWS_WITH(mode("fine"), Catch::Matchers::Contains("resolution-mode"));
}

TEST_CASE("camotics: an automatic workpiece is CAMotics' block from z = 0", "[path][camotics]") {
    // A flat D2 (radius 1) cutting along x from (0, 0) to (40, 20) at one depth, after a rapid
    // from above: CAMotics' block spans the cuts widened by the radius, from z = 0 down to the
    // lowest cut, and 2 mm further where it would be thinner than 2 mm; the margin grows every
    // side but the top.
    ToolTable tools;
    tools.insert_or_assign(1, flatEndMill(2.0, {10.0, 0.0}));
    auto slot = [&](double z) {
        ToolPath path;
        auto add = [&](Vec3 a, Vec3 b, bool rapid) {
            Move m;
            m.start = a;
            m.end = b;
            m.rapid = rapid;
            m.tool = 1;
            path.moves.push_back(m);
        };
        add(Vec3(0, 0, 5), Vec3(0, 0, z), true);
        add(Vec3(0, 0, z), Vec3(40, 0, z), false);
        add(Vec3(40, 0, z), Vec3(40, 20, z), false);
        return path;
    };
    auto check = [](const Box& b, Vec3 lo, Vec3 hi) {
        for (int k = 0; k < 3; ++k) {
            CHECK(b.lo[k] == Approx(lo[k]).margin(1e-12));
            CHECK(b.hi[k] == Approx(hi[k]).margin(1e-12));
        }
    };
    check(automaticWorkpieceBounds(slot(-0.5), tools, 0.0), Vec3(-1, -1, -2.5), Vec3(41, 21, 0));  // an engraving
    check(automaticWorkpieceBounds(slot(-1.0), tools, 0.0), Vec3(-1, -1, -3), Vec3(41, 21, 0));
    check(automaticWorkpieceBounds(slot(-5.0), tools, 0.0), Vec3(-1, -1, -5), Vec3(41, 21, 0));
    // Cuts wholly above z = 0, where CAMotics' box turns inside out (its top at 0 under its
    // bottom at the cuts): ours keeps the top at z = 0 and the least thickness below it.
    check(automaticWorkpieceBounds(slot(3.0), tools, 0.0), Vec3(-1, -1, -2), Vec3(41, 21, 0));
    // 10 %: 4.2 and 2.2 mm on x and y, 0.5 mm below.
    check(automaticWorkpieceBounds(slot(-5.0), tools, 10.0), Vec3(-5.2, -3.2, -5.5), Vec3(45.2, 23.2, 0));

    // CAMotics' defaults where the project leaves the workpiece out: automatic, 5 % margin.
    const Project none = parseCamoticsProject("{}", "p.camotics", "");
    CHECK(none.workpiece.automatic);
    CHECK(none.workpiece.marginPercent == 5.0);
    const Project bare = parseCamoticsProject(R"({"workpiece": {"margin": 1}})", "p.camotics", "");
    CHECK(bare.workpiece.automatic);
    CHECK(bare.workpiece.marginPercent == 1.0);
}

TEST_CASE("camotics: tool shapes by CAMotics' names, in any case", "[path][camotics]") {
    auto tool = [](const std::string& fields) {
        const Project p = parseCamoticsProject(R"({"tools": {"1": {)" + fields + R"(, "length": 10, "diameter": 4}}})",
                                               "p.camotics", "");
        return p.tools.at(1);
    };
    // Flat: radius 2 at the tip; a cone (V-bit): a point at the tip and radius 2 at the length.
    CHECK(tool(R"("shape": "Cylindrical")").radiusAt(0.0) == Approx(2.0));
    CHECK(tool(R"("shape": "cylinder")").radiusAt(0.0) == Approx(2.0));
    CHECK(tool(R"("shape": "BALLNOSE")").radiusAt(0.0) == Approx(0.0).margin(1e-12));
    CHECK(tool(R"("shape": "cone")").radiusAt(0.0) == Approx(0.0).margin(1e-12));
    CHECK(tool(R"("shape": "cone")").radiusAt(5.0) == Approx(1.0));
    // A snub as wide as the tool is a cylinder; no snub, a cone; one between, a taper.
    CHECK(tool(R"("shape": "snubnose", "snub_diameter": 4)").radiusAt(0.0) == Approx(2.0));
    CHECK(tool(R"("shape": "snubnose", "snub_diameter": 4)").radiusAt(5.0) == Approx(2.0));
    CHECK(tool(R"("shape": "snubnose", "snub_diameter": 0)").radiusAt(5.0) == Approx(1.0));
    CHECK(tool(R"("shape": "snubnose")").radiusAt(0.0) == Approx(0.0).margin(1e-12));
    CHECK(tool(R"("shape": "snubnose", "snub_diameter": 2)").radiusAt(5.0) == Approx(1.5));
    CHECK_THROWS_AS(tool(R"("shape": "snubnose", "snub_diameter": 5)"), ParseError);
    // A tool larger than a tool may be is an error that names the size.
    CHECK_THROWS_WITH(parseCamoticsProject(R"({"tools": {"1": {"length": 10, "diameter": 1e155}}})", "p.camotics", ""),
                      Catch::Matchers::Contains("diameter d = 1e+155 mm is beyond the 10000 mm"));

    // CAMotics' spheroid has no cutter here: the number is left for --tool, with a warning.
    const Project p = parseCamoticsProject(
        R"({"tools": {"1": {"shape": "spheroid", "length": 10, "diameter": 4}}})", "p.camotics", "");
    CHECK(p.tools.count(1) == 0);
    REQUIRE(p.diagnostics.size() == 1);
    CHECK(p.diagnostics[0].message.find("spheroid") != std::string::npos);
    CHECK(p.diagnostics[0].message.find("--tool") != std::string::npos);
}

TEST_CASE("camotics: a field of the wrong type is named", "[path][camotics][errors]") {
    CHECK_THROWS_WITH(parseCamoticsProject(R"({"workpiece": {"automatic": "true"}})", "p.camotics", ""),
                      Catch::Matchers::Contains("\"automatic\" must be true or false"));
    CHECK_THROWS_WITH(parseCamoticsProject(R"({"units": 5})", "p.camotics", ""),
                      Catch::Matchers::Contains("\"units\" must be a string"));
    CHECK_THROWS_WITH(parseCamoticsProject(R"({"tools": {"1": {"shape": 2, "length": 1, "diameter": 1}}})",
                                           "p.camotics", ""),
                      Catch::Matchers::Contains("tool 1: \"shape\" must be a string"));
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
    CHECK_THROWS_WITH(parseCamoticsProject(text, "big.camotics", "."),
                      Catch::Matchers::Contains("big.camotics:1:16: error: CAMotics project: the number 5555555E"));
}

TEST_CASE("camotics: an error about what a value means names the value's line and column",
          "[path][camotics][errors]") {
    // The place of the value (or key) at fault, counted by hand; a comment before it hides a key.
    const struct {
        const char* text;
        const char* place;
        const char* message;
    } cases[] = {
        {"{\n  // \"units\": 5\n  \"units\": \"furlongs\"\n}", "p.camotics:3:12: error", "units must be"},
        {R"({"tools": {"1": {"length": 10, "diameter": -1}}})", "p.camotics:1:44: error",
         "tool 1: diameter and length must be positive"},
        {"{\"tools\": {\n  \"x1\": {\"length\": 1, \"diameter\": 1}}}", "p.camotics:2:3: error",
         "tool numbers must be integers"},
        // A missing key: the brace of the object that lacks it.
        {R"({"tools": {"2": {"diameter": 3}}})", "p.camotics:1:17: error", "tool 2: missing \"length\""},
        {"{\"workpiece\": {\"automatic\": false,\n \"bounds\": {\"min\": [0, 0], \"max\": [1, 1, 1]}}}",
         "p.camotics:2:20: error", "workpiece bounds min must be an array of 3 numbers"},
        {R"({"files": ["a.ngc", 7]})", "p.camotics:1:21: error", "a file entry must be a string"},
        {R"({"tools": {"1": {"shape": "oval", "length": 1, "diameter": 1}}})", "p.camotics:1:27: error",
         "unknown tool shape"},
    };
    for (const auto& c : cases) {
        INFO(c.text);
        CHECK_THROWS_WITH(parseCamoticsProject(c.text, "p.camotics", ""),
                          Catch::Contains(c.place) && Catch::Contains(c.message));
    }
    // A warning about a key names the key.
    const Project p = parseCamoticsProject("{\"units\": \"metric\",\r\n \"colour\": 1}", "p.camotics", "");
    REQUIRE(p.diagnostics.size() == 1);
    CHECK(p.diagnostics[0].message == "project entry \"colour\" ignored");
    CHECK(p.diagnostics[0].where.line == 2);
    CHECK(p.diagnostics[0].where.column == 2);
}

TEST_CASE("camotics: a program the project names that is missing or no program is an error at its entry",
          "[path][camotics][errors]") {
    // The entries' places, counted by hand: "gone.ngc" opens at 3:13, the object's "path" value at
    // 4:22, "part.stl" at 5:3.
    const std::string text = "{\"units\": \"metric\",\n"
                             " \"files\": [\"a.ngc\",\n"
                             "            \"gone.ngc\",\n"
                             "            {\"path\": \"sub/lost.ngc\"},\n"
                             "  \"part.stl\"]}";
    const Project p = parseCamoticsProject(text, "dir/p.camotics", "dir");
    REQUIRE(p.files.size() == 4);
    GcodeOptions options;
    options.files = [](const std::string& path) -> std::optional<std::string> {
        if (path == "dir/a.ngc" || path == "dir/part.stl") return std::string("G21\nG0 X0 Y0 Z5\n");
        return std::nullopt;
    };
    const auto errorAt = [&](std::size_t keep) -> std::string {
        Project q = p;
        q.files.erase(q.files.begin() + 1, q.files.begin() + std::ptrdiff_t(keep));
        try {
            runProject(q, options);
        } catch (const ParseError& e) {
            return e.what();
        } catch (const Error& e) {
            return std::string("not at an entry: ") + e.what();
        }
        return "no error";
    };
    CHECK(errorAt(1) == "dir/p.camotics:3:13: error: cannot open 'dir/gone.ngc': no such file");
    CHECK(errorAt(2) == "dir/p.camotics:4:22: error: cannot open 'dir/sub/lost.ngc': no such file");
    CHECK_THAT(errorAt(3), Catch::StartsWith("dir/p.camotics:5:3: error: 'dir/part.stl' is an STL mesh, not a program"));
    // A program given in the project's place has no entry: its error names the file alone.
    Project given = p;
    given.files = {{"elsewhere.ngc", {}}};
    CHECK_THROWS_WITH(runProject(given, options), "cannot open 'elsewhere.ngc': no such file");
}

TEST_CASE("camotics: a key CAMotics does not read, in a tool, the workpiece, its bounds or a program entry, is "
          "named at its place",
          "[path][camotics]") {
    // Places of the keys found with Python's str.index, 1-based.
    const std::string text = "{\"tools\": {\"1\": {\"shape\": \"ballnose\", \"length\": 10, \"diametre\": 6,\n"
                             "                  \"diameter\": 6, \"description\": \"\", \"number\": 1},\n"
                             "           \"2\": {\"length\": 10, \"diameter\": 2}},\n"
                             " \"workpiece\": {\"automatic\": false, \"colour\": \"oak\",\n"
                             "   \"bounds\": {\"min\": [0, 0, -5], \"max\": [10, 10, 0], \"centre\": [5, 5, 0]}},\n"
                             " \"files\": [\"a.ngc\", {\"path\": \"b.ngc\", \"open\": true}]}";
    const Project p = parseCamoticsProject(text, "p.camotics", "");
    const struct {
        const char* message;
        int line, column;
    } expected[] = {
        {"tool 1 entry \"diametre\" ignored", 1, 53},
        {"workpiece entry \"colour\" ignored", 4, 36},
        {"workpiece bounds entry \"centre\" ignored", 5, 54},
        {"program 2 entry \"open\" ignored", 6, 39},
    };
    REQUIRE(p.diagnostics.size() == std::size(expected));
    for (std::size_t i = 0; i < std::size(expected); ++i) {
        INFO(expected[i].message);
        CHECK(p.diagnostics[i].severity == Diagnostic::Severity::Warning);
        CHECK(p.diagnostics[i].message == expected[i].message);
        CHECK(p.diagnostics[i].where.line == expected[i].line);
        CHECK(p.diagnostics[i].where.column == expected[i].column);
    }
    // What the keys CAMotics reads say still holds.
    CHECK(p.tools.at(1).cuttingRadius() == 3.0);
    CHECK(p.tools.at(2).cuttingRadius() == 1.0);
    CHECK(p.workpiece.bounds.hi.x == 10.0);
    REQUIRE(p.files.size() == 2);
    CHECK(p.files[1].path == "b.ngc");
}

TEST_CASE("camotics: a tool is numbered by its \"number\", and of two with one number the later is kept, as in "
          "CAMotics",
          "[path][camotics]") {
    // CAMotics' Tool::read sets the tool's number from "number", its key's by default, and its
    // ToolTable keeps the later of two with one number. Places found with Python's str.index.
    const std::string text = "{\"tools\": {\"2\": {\"length\": 9, \"diameter\": 4, \"number\": 7},\n"
                             "           \"10\": {\"length\": 9, \"diameter\": 6, \"number\": 3},\n"
                             "           \"3\": {\"length\": 9, \"diameter\": 8}}}";
    const Project p = parseCamoticsProject(text, "p.camotics", "");
    // Key 2 is tool 7; key 10 is tool 3, which key 3, later in the file, replaces. No tool 2 or 10.
    REQUIRE(p.tools.size() == 2);
    CHECK(p.tools.at(7).cuttingRadius() == 2.0);
    CHECK(p.tools.at(3).cuttingRadius() == 4.0);
    CHECK(p.tools.count(2) == 0);
    CHECK(p.tools.count(10) == 0);
    const auto said = [&](const std::string& fragment) -> const Diagnostic* {
        for (const Diagnostic& d : p.diagnostics)
            if (d.message.find(fragment) != std::string::npos) return &d;
        return nullptr;
    };
    const Diagnostic* renumbered = said("tool 2 is tool 7: CAMotics numbers a project's tool by its \"number\"");
    REQUIRE(renumbered);
    CHECK(renumbered->severity == Diagnostic::Severity::Note);
    CHECK(renumbered->where.line == 1);
    CHECK(renumbered->where.column == 56);
    const Diagnostic* replaced =
        said("tool 10 (tool 3) is replaced by tool 3 at line 3, which has its number: CAMotics keeps the later");
    REQUIRE(replaced);
    CHECK(replaced->severity == Diagnostic::Severity::Warning);
    CHECK(replaced->where.line == 2);
    CHECK(replaced->where.column == 12);
    // A "number" that is no tool number is an error at its value.
    for (const char* bad : {"-1", "2.5", "\"4\"", "1e12"}) {
        INFO(bad);
        const std::string t =
            std::string("{\"tools\": {\"1\": {\"length\": 9, \"diameter\": 4, \"number\": ") + bad + "}}}";
        try {
            parseCamoticsProject(t, "p.camotics", "");
            FAIL("no error");
        } catch (const ParseError& e) {
            CHECK_THAT(e.what(), Catch::Matchers::Contains("tool 1: \"number\" must be a whole number from 0"));
            CHECK(e.where().line == 1);
            CHECK(e.where().column == 56);
        }
    }
}
