// The dexelmill executable: exit codes, messages and outputs as a user sees them.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "support/cli_run.h"
#include "support/temp_dir.h"

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using dexelmill::testing::Cli;
using dexelmill::testing::Run;
using dexelmill::testing::slurp;
namespace fs = std::filesystem;

namespace {

/// The box [lo, hi] as ASCII STL, two triangles a face, facing out.
std::string boxStl(const std::array<double, 3>& lo, const std::array<double, 3>& hi) {
    std::string s = "solid box\n";
    auto corner = [&](int bits) {
        return std::to_string((bits & 1) ? hi[0] : lo[0]) + " " + std::to_string((bits & 2) ? hi[1] : lo[1]) + " " +
               std::to_string((bits & 4) ? hi[2] : lo[2]);
    };
    // Each face's corners counter-clockwise seen from outside (bit 0: x, 1: y, 2: z high).
    for (const std::array<int, 4>& q : {std::array<int, 4>{0, 4, 6, 2}, std::array<int, 4>{1, 3, 7, 5},
                                        std::array<int, 4>{0, 1, 5, 4}, std::array<int, 4>{2, 6, 7, 3},
                                        std::array<int, 4>{0, 2, 3, 1}, std::array<int, 4>{4, 5, 7, 6}})
        for (const std::array<int, 3>& t : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}})
            s += " facet normal 0 0 0\n  outer loop\n   vertex " + corner(q[std::size_t(t[0])]) + "\n   vertex " +
                 corner(q[std::size_t(t[1])]) + "\n   vertex " + corner(q[std::size_t(t[2])]) +
                 "\n  endloop\n endfacet\n";
    return s + "endsolid box\n";
}

}  // namespace

TEST_CASE("help and version explain themselves and exit 0", "[cli]") {
    const Cli cli("help");
    Run r = cli("--help");
    CHECK(r.code == 0);
    CHECK_THAT(r.out, Contains("simulate") && Contains("info") && Contains("study") && Contains("mm"));
    r = cli("simulate --help");
    CHECK(r.code == 0);
    CHECK_THAT(r.out, Contains("--stock") && Contains("--tool") && Contains("ball:d=6") && Contains("--resolution"));
    r = cli("--version");
    CHECK(r.code == 0);
    CHECK_THAT(r.out, Contains("dexelmill"));
}

TEST_CASE("malformed invocations exit 2 with a helpful message", "[cli][errors]") {
    const Cli cli("usage");
    cli.file("ok.ngc", "G21\nG0 X0 Y0 Z5\nG1 X5 F100\n");
    CHECK(cli("").code == 2);
    Run r = cli("frobnicate");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, StartsWith("dexelmill: unknown command 'frobnicate'") && Contains("simulate, compare, info and study"));
    r = cli("simulate");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("INPUTS"));
    r = cli("simulate ok.ngc --bogus");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, StartsWith("dexelmill: ") && Contains("--bogus") && Contains("'dexelmill simulate --help'"));
    r = cli("simulate ok.ngc --tool ball:d=x");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("'x' is not a number"));
    r = cli("simulate ok.ngc --tool-table-units inch --tool flat:d=3");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("--tool-table-units needs --tool-table FILE.tbl"));
    r = cli("simulate ok.ngc --tool-table t.tbl --tool-table-units cm");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("--tool-table-units must be mm or inch, got 'cm'"));
    r = cli("simulate ok.ngc --tool bull:d=10,r=7");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("corner radius r = 7"));
    r = cli("simulate ok.ngc --tool flat:d=3 --stock box:0,0,0,10,10");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("6 numbers"));
    r = cli("simulate ok.ngc --tool flat:d=3 --stock box:0,0,0,-10,10,10");
    CHECK(r.code == 2);
    r = cli("simulate ok.ngc --tool flat:d=3 --stock cylinder:w,0,0,0,5,10");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("the axis 'w' is not x, y or z"));
    r = cli("simulate ok.ngc --tool flat:d=3 --stock cone:z,0,0,0,5,10");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("cone:AXIS,X,Y,Z,R0,R1,H") && Contains("6 numbers"));
    r = cli("simulate ok.ngc --tool flat:d=3 --stock cone:-z,0,0,0,0,0,10");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("positive radius"));
    r = cli("simulate ok.ngc --tool flat:d=3 --families xw");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("x, y and z"));
    r = cli("study ok.ngc --case tilted-slot");
    CHECK(r.code == 2);
    r = cli("study --case tilted-slot --resolutions 1,zero");
    CHECK(r.code == 2);
    r = cli("study --case tilted-slot --tool flat:d=20");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("--tool: a --case cuts with its own tools"));
    r = cli("study --case tilted-slot --tool-table t.tbl");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("--tool-table: a --case cuts with its own tools"));
    r = cli("study --case tilted-slot --tool 1=flat:d=20");
    CHECK(r.code == 2);
    r = cli("study --case nope");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("bull-undercut") && Contains("dexelmill study --help"));
    // Counts of points, read as unsigned: -1 must not wrap around to 2^64 - 1.
    for (const auto& [args, says] : {std::pair<const char*, const char*>{"--surface-points -1", "--surface-points: must be positive, got -1"},
                                     {"--surface-points 0", "--surface-points: must be positive, got 0"},
                                     {"--samples -5", "--samples: must be positive, got -5"},
                                     {"--samples 0", "--samples: must be positive, got 0"}}) {
        INFO(args);
        r = cli(std::string("study --case v-carve ") + args);
        CHECK(r.code == 2);
        CHECK_THAT(r.err, StartsWith("dexelmill: ") && Contains(says) &&
                              Contains("Run 'dexelmill study --help' for usage."));
    }
    r = cli("study --case v-carve --surface-points 1000000000000 --max-memory 1G");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("--surface-points") && Contains("--samples") && !Contains("out of memory"));
    // Values an option cannot take name the option and the value, not an internal field.
    for (const auto& [args, says] : {std::pair<const char*, const char*>{"--chord-tolerance 0", "--chord-tolerance: must be positive, got 0"},
                                     {"--resolution 0", "--resolution: must be positive, got 0"},
                                     {"--resolution -0.5", "--resolution: must be positive, got -0.5"},
                                     {"--resolution 1x", "'1x' is not a number"},
                                     {"--threads -3", "--threads: must be 0 or more, got -3"},
                                     {"--refine 9", "--refine"},
                                     {"--refine-tolerance 0", "--refine-tolerance: must be positive, got 0"},
                                     {"--gouge-csv g.csv", "--gouge-csv needs --design"},
                                     {"--deviation-ply d.ply", "--deviation-ply needs --design"},
                                     {"--design-transform 1,2,3", "--design-transform needs --design"},
                                     {"--design d.stl --design-transform 1,2", "TX,TY,TZ or the 3 rows"},
                                     {"--design d.stl --design-transform 1,2,z", "'z' is not a number"},
                                     {"--gouge-tolerance -1", "--gouge-tolerance"},
                                     // Options that serve another option are refused without it.
                                     {"--gouge-tolerance 0.1", "--gouge-tolerance needs --design"},
                                     {"--excess-tolerance 0.1", "--excess-tolerance needs --design"},
                                     {"--refine-tolerance 0.5", "--refine-tolerance needs --refine"},
                                     {"-o ''", "--output: the path is empty"},
                                     {"--report ''", "--report: the path is empty"},
                                     {"--stock box:0x10,0,0,20,20,5", "--stock box: '0x10' is not a number"},
                                     {"--start 1e300,0,-5", "--start: 1e+300 mm is beyond the 1e9 mm a program may reach"},
                                     // Decimal only, as --stock and --tool (strtod reads 0x10 as 16).
                                     {"--max-memory 0x10G", "--max-memory: '0x10G' is not a memory size"},
                                     {"--resolution 0x.8", "--resolution: '0x.8' is not a number"},
                                     {"--adaptivity 0x0.8", "--adaptivity: '0x0.8' is not a number"},
                                     {"--refine 0x1", "--refine: '0x1' is not a number"},
                                     // An empty field is an error, not a field less.
                                     {"--stock box:0,0,-5,20,20,0,", "--stock box: '0,0,-5,20,20,0,' has an empty value"},
                                     {"--start 1,2,", "--start: '1,2,' has an empty value"},
                                     // Stock where a program may not reach: its sizes there are lost to rounding.
                                     {"--stock box:0,0,-5,20,20,2e9",
                                      "--stock box: ZMAX = 2e+09 mm is beyond the 1e9 mm a program may reach"},
                                     {"--stock cylinder:z,0,0,1e300,5,10",
                                      "--stock cylinder:AXIS,X,Y,Z,R,H: Z = 1e+300 mm is beyond the 1e9 mm"},
                                     {"--stock cone:x,0,0,0,5,2,-3e9", "--stock cone:AXIS,X,Y,Z,R0,R1,H: H = -3e+09 mm is beyond"}}) {
        INFO(args);
        r = cli(std::string("simulate ok.ngc --tool flat:d=3 ") + args);
        CHECK(r.code == 2);
        CHECK_THAT(r.err, Contains(says));
        CHECK_THAT(r.err, !Contains("Options::"));
        // CLI11's own errors (ranges, numbers) read as the tool's: named, with the command's help.
        CHECK_THAT(r.err, StartsWith("dexelmill: ") && Contains("Run 'dexelmill simulate --help' for usage."));
    }
    // A tool larger than a tool may be is refused, not swept (the square of 1e155 overflows).
    for (const char* tool : {"flat:d=1e155", "ball:d=1e155", "flat:d=6,total=1e300"}) {
        INFO(tool);
        r = cli(std::string("simulate ok.ngc --stock box:0,0,-5,20,20,0 --resolution 0.5 -q --tool ") + tool);
        CHECK(r.code == 2);
        CHECK_THAT(r.err, Contains("mm is beyond the 10000 mm a tool may measure"));
    }
    // A tool spec's numbers are decimal too.
    r = cli("simulate ok.ngc --tool flat:d=0x6");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("'0x6' is not a number"));
    // A stock the program cannot read names every form it takes.
    for (const char* stock : {"sphere:1,2,3", "Box:0,0,0,10,10,10"}) {
        INFO(stock);
        r = cli(std::string("simulate ok.ngc --tool flat:d=3 --stock ") + stock);
        CHECK(r.code == 1);
        CHECK_THAT(r.err, Contains("box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX") && Contains("cylinder:AXIS,X,Y,Z,R,H") &&
                              Contains("cone:AXIS,X,Y,Z,R0,R1,H") && Contains(".stl") && Contains(".vdb"));
    }
    r = cli("study --case v-carve --resolutions 1,");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("--resolutions: '' is not a positive number"));
    r = cli("simulate ok.ngc --tool flat:d=3 --machine .");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("--machine '.': a folder"));
}

namespace {

/// The box [0, 10] x [0, 10] x [0, top] as ASCII STL, facing out.
std::string boxStl(double top) {
    const double c[8][3] = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {10, 10, 0}, {0, 0, top}, {10, 0, top}, {0, 10, top}, {10, 10, top}};
    const int f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    std::string s = "solid box\n";
    for (const auto& q : f)
        for (const auto& t : {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
            s += "facet normal 0 0 0\nouter loop\n";
            for (int v : t)
                s += "vertex " + std::to_string(c[v][0]) + " " + std::to_string(c[v][1]) + " " + std::to_string(c[v][2]) + "\n";
            s += "endloop\nendfacet\n";
        }
    return s + "endsolid box\n";
}

}  // namespace

TEST_CASE("an option that takes one value, given twice, is named", "[cli][errors]") {
    const Cli cli("twice");
    // Every option of every command that takes one value, each with a value it accepts: the
    // second is refused for being there, not for what it says.
    const std::vector<std::pair<const char*, std::vector<std::pair<const char*, const char*>>>> commands = {
        {"simulate ok.ngc",
         {{"--stock", "box:0,0,-5,20,20,0"}, {"--chord-tolerance", "0.01"}, {"--turn-tolerance", "0.01"},
          {"--machine", "xyza"}, {"--start", "0,0,0"}, {"--mesher", "vdb"}, {"--refine", "1"},
          {"--refine-tolerance", "0.01"}, {"--threads", "1"}, {"--max-memory", "1G"}, {"--resolution", "1"},
          {"--families", "xyz"}, {"--output", "a.stl"}, {"--vdb", "a.vdb"}, {"--png", "a.png"},
          {"--report", "a.json"}, {"--design", "d.stl"}, {"--design-transform", "1,2,3"},
          {"--gouge-tolerance", "0.1"}, {"--excess-tolerance", "0.1"}, {"--gouge-csv", "g.csv"},
          {"--deviation-ply", "d.ply"}, {"--adaptivity", "0.1"}}},
        {"study",
         {{"--stock", "box:0,0,-5,20,20,0"}, {"--chord-tolerance", "0.01"}, {"--turn-tolerance", "0.01"},
          {"--machine", "xyza"}, {"--start", "0,0,0"}, {"--mesher", "vdb"}, {"--refine", "1"},
          {"--refine-tolerance", "0.01"}, {"--threads", "1"}, {"--max-memory", "1G"}, {"--case", "v-carve"},
          {"--resolutions", "1"}, {"--families", "z"}, {"--csv", "a.csv"}, {"--plot", "a.png"},
          {"--ply-deviation", "plies"}, {"--surface-points", "10"}, {"--samples", "10"}}},
        {"compare a.stl b.stl",
         {{"--design-transform", "1,2,3"}, {"--gouge-tolerance", "0.1"}, {"--excess-tolerance", "0.1"},
          {"--ply", "a.ply"}, {"--png", "a.png"}, {"--report", "a.json"}, {"--threads", "1"}}},
        {"info ok.ngc", {{"--machine", "xyza"}, {"--start", "0,0,0"}}}};
    for (const auto& [command, options] : commands)
        for (const auto& [option, value] : options) {
            const std::string given = std::string(" ") + option + " " + value;
            INFO(command << given << given);
            const Run r = cli(command + given + given);
            CHECK(r.code == 2);
            const std::string name = std::string(command).substr(0, std::string(command).find(' '));
            CHECK_THAT(r.err, StartsWith(std::string("dexelmill: ") + option + " is given twice; it takes one value\n") &&
                                  Contains("Run 'dexelmill " + name + " --help' for usage."));
        }
    // Three times, and by its short name.
    const Run r = cli("simulate ok.ngc -o a.stl -o b.stl --output c.stl");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, StartsWith("dexelmill: --output is given 3 times; it takes one value\n"));
    // Another option's missing value is named as CLI11 names it, not taken for the repetition.
    const Run missing = cli("simulate ok.ngc --resolution 1 --resolution 2 --stock");
    CHECK(missing.code == 2);
    CHECK_THAT(missing.err, StartsWith("dexelmill: --stock") && !Contains("given twice"));
    // Repeatable options and flags are not refused.
    cli.file("ok.ngc", "G21\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X5\n");
    const Run repeated =
        cli("simulate ok.ngc --tool flat:d=3 --tool 2=ball:d=2 --stock box:0,0,-5,20,20,0 --resolution 1 -q -q");
    CHECK(repeated.code == 0);
}

TEST_CASE("compare measures a part against the design and writes its files", "[cli][compare]") {
    const Cli cli("compare");
    cli.file("part.stl", boxStl(10.0));
    cli.file("design.stl", boxStl(9.875));
    Run r = cli("compare part.stl design.stl --ply dev.ply --png dev.png --report dev.json --threads 1");
    INFO(r.err);
    CHECK(r.code == 0);
    // The top face stands 0.125 mm above the design's: excess; so do the sides' top 0.125 mm, by
    // z - 9.875. The bin from 0.1 to 0.25 mm holds the top (100 mm^2) and the sides' top 0.025 mm
    // (1 mm^2), to within twice the sampling's spacing along the 40 mm where the sides cross 0.1.
    CHECK_THAT(r.out, Contains("within tolerance") && Contains("farthest 0.125 mm outside") && Contains("deepest 0 mm"));
    const std::size_t bound = r.out.find("within ");
    REQUIRE(bound != std::string::npos);
    const double spacing = std::sqrt(3.0) * std::stod(r.out.substr(bound + 7));
    // 12 right triangles with 10 mm legs: 2^16 points allow k = 103 copies along each edge, a
    // spacing of 10 sqrt(2) / 103 = 0.137 mm, found to within 2 %.
    CHECK(spacing < 0.1373 * 1.02 + 0.001);
    const std::size_t row = r.out.find("+0.1 .. +0.25");
    REQUIRE(row != std::string::npos);
    const double area = std::stod(r.out.substr(row + 13));
    CHECK(area == Approx(101.0).margin(2.0 * spacing * 40.0));
    for (const char* f : {"dev.ply", "dev.png", "dev.json"}) CHECK(fs::file_size(cli.dir() / f) > 100);
    // The format number of the report's keys, as the README gives it.
    CHECK(nlohmann::json::parse(slurp(cli.dir() / "dev.json"))["format"] == 1);
    CHECK(cli("compare part.stl").code == 2);
    r = cli("compare part.stl missing.stl");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("missing.stl"));
    r = cli("compare part.stl design.stl --excess-tolerance -1");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Contains("--excess-tolerance: must be 0 or more, got -1"));
}

TEST_CASE("compare prints a part that matches its design as 0 mm off and no number with an exponent",
          "[cli][compare]") {
    const Cli cli("compare_match");
    // An uncut block meshed at 0.7 mm: its vertices lie on the box's faces, between its corners,
    // where their distances come out as rounding (1e-14 mm) unless taken as 0.
    cli.file("none.ngc", "G21 G90\nG0 X0 Y0 Z50\nM30\n");
    cli.file("box.stl", boxStl({0, 0, 0}, {40, 30, 10}));
    Run r = cli("simulate none.ngc --stock box:0,0,0,40,30,10 --tool flat:d=6 --resolution 0.7 -q -o uncut.stl");
    REQUIRE(r.code == 0);
    r = cli("compare uncut.stl box.stl --gouge-tolerance 0 --excess-tolerance 0");
    INFO(r.out);
    CHECK(r.code == 0);
    CHECK_THAT(r.out, Contains("deepest 0 mm") && Contains("farthest 0 mm outside") && Contains("RMS 0 mm"));
    // All of it lies within the tolerances of 0: no bin of rounding beside it.
    CHECK_THAT(r.out, Contains("tolerances -0 / +0 mm") && Contains("  0 .. 0  ") && Contains("100.00"));
    CHECK_THAT(r.out, !Contains("0 .. +0.001") && !Contains("-0.001 .. 0"));
    const auto exponent = [](const std::string& text) { return std::regex_search(text, std::regex("[0-9][eE][-+]?[0-9]")); };
    CHECK_FALSE(exponent(r.out));
    // Tolerances below a nanometre print as 0 too, not as 1e-300.
    r = cli("compare uncut.stl box.stl --gouge-tolerance 1e-300 --excess-tolerance 1e-300");
    CHECK(r.code == 0);
    CHECK_FALSE(exponent(r.out));
}

TEST_CASE("input errors exit 1 with file:line:col", "[cli][errors]") {
    const Cli cli("input");
    cli.file("bad.ngc", "G21\nG0 X0 Y0 Z5\nG1 X1.2.3 F100\n");
    Run r = cli("simulate bad.ngc --tool flat:d=3 --stock box:0,0,0,10,10,10 -o part.obj");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("bad.ngc:3:") && Contains("error"));
    CHECK_FALSE(fs::exists(cli.dir() / "part.obj"));
    r = cli("simulate nowhere.ngc --tool flat:d=3");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("nowhere.ngc"));
    cli.file("ok.ngc", "G21\nT1 M6\nG0 X0 Y0 Z5\nG1 X5 F100\n");
    cli.file("bad.tbl", "T1 P1 D3\nT2 P2 D-4\n");
    for (const auto& [table, says] : {std::pair<std::string, std::string>{"bad.tbl", "bad.tbl:2:7: error: the tool table's "
                                                                                     "diameter D must not be negative"},
                                      {"nowhere.tbl", "cannot open 'nowhere.tbl'"}}) {
        r = cli("simulate ok.ngc --stock box:0,0,0,10,10,10 --tool-table " + table);
        CHECK(r.code == 1);
        CHECK_THAT(r.err, Contains(says));
    }
    r = cli("info nowhere.apt");
    CHECK(r.code == 1);
    // A solid where a program belongs is named as what it is, not read as G-code.
    cli.file("design.stl", boxStl({0, 0, 0}, {10, 10, 10}));
    for (const char* args : {"simulate design.stl --tool flat:d=3", "info design.stl"}) {
        INFO(args);
        r = cli(args);
        CHECK(r.code == 1);
        CHECK_THAT(r.err, StartsWith("dexelmill: error: 'design.stl' is an STL mesh, not a program"));
    }
    // An output in a folder that is not there fails before the cut, naming it; the other outputs
    // are not written.
    cli.file("ok.ngc", "G21\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X5\n");
    r = cli("simulate ok.ngc --tool flat:d=3 --stock nowhere.stl");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("cannot open 'nowhere.stl': No such file or directory"));
    r = cli("simulate ok.ngc --tool flat:d=3 --stock box:0,0,-5,10,10,0 -o part.stl --report missing/r.json");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("missing/r.json") && Contains("No such file or directory"));
    CHECK_FALSE(fs::exists(cli.dir() / "part.stl"));
    fs::create_directories(cli.dir() / "sub.json");
    r = cli("simulate ok.ngc --tool flat:d=3 --stock box:0,0,-5,10,10,0 -o part.stl --report sub.json");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("'sub.json': it is a folder"));
    CHECK_FALSE(fs::exists(cli.dir() / "part.stl"));
}

namespace {

/// Makes `path` a device that fails every write as a full disk does: a node of /dev/full's numbers
/// of its own (root may make one), else a link to /dev/full (which a user cannot replace). False
/// where neither fails so.
bool makeFullDisk(const fs::path& path) {
    if (::mknod(path.c_str(), S_IFCHR | 0666, ::makedev(1, 7)) != 0) {
        std::error_code ec;
        fs::create_symlink("/dev/full", path, ec);
        if (ec) return false;
    }
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) return false;
    const bool full = ::write(fd, "x", 1) < 0 && errno == ENOSPC;
    ::close(fd);
    return full;
}

std::size_t entries(const fs::path& dir) {
    return std::size_t(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

}  // namespace

TEST_CASE("a run that fails writing its last output leaves the outputs written before as they were",
          "[cli][errors]") {
    const Cli cli("full_disk");
    cli.file("slot.ngc", "G21 G90\nT1 M6\nG0 X5 Y15 Z15\nG1 Z7 F100\nG1 X35\nG0 Z15\nM30\n");
    cli.file("part.stl", boxStl(10.0));
    cli.file("design.stl", boxStl(9.875));
    for (const char* f : {"keep.stl", "keep.png", "keep.ply", "keep.csv"}) cli.file(f, "KEEP\n");
    if (!makeFullDisk(cli.dir() / "full.json") || !makeFullDisk(cli.dir() / "full.png")) {
        WARN("no device that fails as a full disk (/dev/full): skipped");
        return;
    }
    const std::size_t before = entries(cli.dir()) + 2;  // out.txt and err.txt
    // The report (or the study's plot) is written last: the full disk fails it.
    Run r = cli("simulate slot.ngc --stock box:0,0,0,40,30,10 --tool 1=flat:d=6 --resolution 0.5 -q "
                "-o keep.stl --png keep.png --report full.json");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("full.json"));
    r = cli("compare part.stl design.stl --ply keep.ply --png keep.png --report full.json");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("full.json"));
    r = cli("study --case tilted-slot --resolutions 2 --families z --surface-points 100 --samples 100 --quiet "
            "--csv keep.csv --plot full.png");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("full.png"));
    for (const char* f : {"keep.stl", "keep.png", "keep.ply", "keep.csv"}) {
        INFO(f);
        CHECK(slurp(cli.dir() / f) == "KEEP\n");
    }
    CHECK(entries(cli.dir()) == before);  // no temporary file left
}

TEST_CASE("a run ended by a signal while it writes leaves no temporary file", "[cli][errors]") {
    const Cli cli("signal");
    cli.file("slot.ngc", "G21 G90\nT1 M6\nG0 X5 Y15 Z15\nG1 Z7 F100\nG1 X35\nG0 Z15\nM30\n");
    cli.file("keep.stl", "KEEP\n");
    // The report goes to a FIFO no one reads, written in place and last: the run stops there, its
    // mesh staged beside keep.stl, until SIGTERM ends it (a shell's background job ignores SIGINT).
    REQUIRE(::mkfifo((cli.dir() / "report.json").c_str(), 0600) == 0);
    const Run r = cli.runIn(std::string("('") + DEXELMILL_CLI_PATH +
                            "' simulate slot.ngc --stock box:0,0,0,40,30,10 --tool 1=flat:d=6 --resolution 0.5 -q "
                            "-o keep.stl --report report.json & pid=$!; "
                            "for i in $(seq 1 600); do ls -a | grep -q '^\\.keep\\.stl\\.tmp' && break; sleep 0.1; done; "
                            "ls -a | grep -c '^\\.keep\\.stl\\.tmp'; kill -TERM $pid; wait $pid; echo \"status $?\")");
    // The temporary file was there, and the signal ended the run (128 + 15) and took it away.
    CHECK_THAT(r.out, StartsWith("1\n") && Contains("status 143"));
    CHECK(slurp(cli.dir() / "keep.stl") == "KEEP\n");
    for (const auto& e : fs::directory_iterator(cli.dir())) {
        INFO(e.path());
        CHECK(e.path().filename().string().find(".tmp") == std::string::npos);
    }
}

TEST_CASE("compare and study check their outputs before any work", "[cli][errors]") {
    const Cli cli("outputs_first");
    cli.file("part.stl", boxStl(10.0));
    cli.file("design.stl", boxStl(9.875));
    for (const char* f : {"keep.ply", "keep.png", "keep.csv"}) cli.file(f, "KEEP\n");
    Run r = cli("compare part.stl design.stl --ply keep.ply --png keep.png --report missing/r.json");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("missing/r.json") && Contains("No such file or directory"));
    // Before the parts are read.
    r = cli("compare part.stl nowhere.stl --report missing/r.json");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("missing/r.json") && !Contains("nowhere.stl"));
    // Before the program is read, and so before the runs.
    cli.file("bad.ngc", "G21\nG1 X1..5\n");
    fs::create_directories(cli.dir() / "table.csv");
    const std::string study = "study bad.ngc --tool flat:d=3 --stock box:0,0,-5,20,20,0 ";
    for (const auto& [args, says] : {std::pair<const char*, const char*>{"--csv table.csv", "'table.csv': it is a folder"},
                                     {"--csv table.txt", "'table.txt': the table is written as .csv"},
                                     {"--plot plot.jpg", "'plot.jpg': the plot is written as .png"},
                                     {"--plot missing/p.png", "missing/p.png"}}) {
        INFO(args);
        r = cli(study + args);
        CHECK(r.code == 1);
        CHECK_THAT(r.err, Contains(says) && !Contains("bad.ngc"));
    }
    r = cli("study --case tilted-slot --resolutions 2 --families z --csv keep.csv --plot missing/p.png");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("missing/p.png"));
    for (const char* f : {"keep.ply", "keep.png", "keep.csv"}) {
        INFO(f);
        CHECK(slurp(cli.dir() / f) == "KEEP\n");
    }
}

TEST_CASE("an output that is an input or another output is refused before any work, naming both",
          "[cli][errors]") {
    const Cli cli("same_file");
    cli.file("p1.ngc", "G21\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\n");
    cli.file("d2.stl", boxStl(10.0));
    cli.file("part.stl", boxStl(10.0));
    fs::create_symlink("p1.ngc", cli.dir() / "p1link.json");
    fs::create_symlink("p1.ngc", cli.dir() / "p1link.png");
    fs::create_symlink("part.stl", cli.dir() / "partlink.json");
    fs::create_symlink("t.csv", cli.dir() / "t.png");  // to a file not made yet
    const std::string run = "simulate p1.ngc --stock box:0,0,-5,20,20,0 --resolution 0.5 -q --tool ball:d=6 ";
    for (const auto& [args, says] :
         {std::pair<const char*, const char*>{"--report p1link.json", "--report 'p1link.json' is the same file as INPUTS 'p1.ngc'"},
          {"--design d2.stl -o d2.stl", "-o 'd2.stl' is the same file as --design 'd2.stl'"},
          {"--design d2.stl -o both.ply --deviation-ply both.ply", "-o 'both.ply' and --deviation-ply 'both.ply' are the same file"},
          {"-o same.stl --report same.stl", "output 'same.stl': the report is written as .json"}}) {
        INFO(args);
        const Run r = cli(run + args);
        CHECK(r.code == 1);
        CHECK_THAT(r.err, Contains(says));
    }
    Run r = cli("compare part.stl d2.stl --report partlink.json");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("--report 'partlink.json' is the same file as MACHINED 'part.stl'"));
    r = cli("study --case tilted-slot --resolutions 2 --families z --csv t.csv --plot t.png");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("--csv 't.csv' and --plot 't.png' are the same file"));
    r = cli("study p1.ngc --stock box:0,0,-5,20,20,0 --tool ball:d=6 --plot p1link.png");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("--plot 'p1link.png' is the same file as INPUTS 'p1.ngc'"));
    // The inputs are as they were, and no output was made.
    CHECK(slurp(cli.dir() / "p1.ngc") == "G21\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\n");
    CHECK(slurp(cli.dir() / "d2.stl") == boxStl(10.0));
    CHECK(slurp(cli.dir() / "part.stl") == boxStl(10.0));
    for (const char* f : {"both.ply", "same.stl", "t.csv"}) CHECK_FALSE(fs::exists(cli.dir() / f));
}

TEST_CASE("every stage honours --threads N: the job starts at most N - 1 workers", "[cli][threads]") {
    // A fresh process per run, so that the workers counted are the job's: TBB starts one only when
    // an arena of the job asks for it (cutting, rebuild, meshing, checks and writing all run in
    // arenas of the requested size).
    const Cli cli("threads");
    std::string raster = "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F100\n";
    for (int k = 0; k <= 40; ++k) raster += "G1 Y" + std::to_string(k) + "\nG1 X" + (k % 2 ? "0" : "40") + "\n";
    cli.file("raster.ngc", raster);
    for (int threads : {1, 2}) {
        INFO("--threads " << threads);
        const std::string report = "r" + std::to_string(threads) + ".json";
        const Run r = cli("simulate raster.ngc --stock box:-5,-5,-5,45,45,0 --tool 1=ball:d=4 --resolution 0.1 "
                          "--png part.png -o part.stl -q --threads " + std::to_string(threads) + " --report " + report);
        REQUIRE(r.code == 0);
        const std::string json = slurp(cli.dir() / report);
        const std::size_t at = json.find("\"threads_started\": ");
        REQUIRE(at != std::string::npos);
        const int started = std::atoi(json.c_str() + at + 19);
        CHECK(started <= threads - 1);
    }
}

/// The kernel's transparent huge page mode, as its setting shows it ("[madvise]" -> "madvise").
std::string hugePageMode() {
    const std::string line = slurp("/sys/kernel/mm/transparent_hugepage/enabled");
    const std::size_t open = line.find('['), close = line.find(']');
    return open == std::string::npos || close == std::string::npos ? "" : line.substr(open + 1, close - open - 1);
}

/// Whether this build's malloc is glibc's, reading glibc.malloc.hugetlb (2.35 and later).
bool glibcMallocWithHugeHeapTunable() {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    return false;
#elif defined(__GLIBC__)
    return __GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 35);
#else
    return false;
#endif
}

TEST_CASE("the launcher starts the tool with malloc's heap on huge pages where the kernel gives them on advice",
          "[cli][memory]") {
    const Cli cli("hugeheap");
    cli.file("slot.ngc", "G21 G90\nT1 M6\nG0 X5 Y15 Z15\nG1 Z7 F100\nG1 X35\nG0 Z15\nM30\n");
    auto run = [&](const std::string& env, bool& onHugePages) {
        const Run r = cli("simulate slot.ngc --stock box:0,0,0,40,30,10 --tool 1=flat:d=6 --resolution 0.5 -q "
                          "--report r.json", env);
        REQUIRE(r.code == 0);
        const std::string json = slurp(cli.dir() / "r.json");
        onHugePages = json.find("\"heap_huge_pages\": true") != std::string::npos;
        CHECK(onHugePages != (json.find("\"heap_huge_pages\": false") != std::string::npos));
        return r;
    };
    const bool glibc = glibcMallocWithHugeHeapTunable();
    bool on = false;
    // The launcher adds the tunable only where advice alone gives huge pages, and keeps others.
    run("env -u GLIBC_TUNABLES", on);
    CHECK(on == (glibc && hugePageMode() == "madvise"));
    run("GLIBC_TUNABLES=glibc.malloc.check=0", on);
    CHECK(on == (glibc && hugePageMode() == "madvise"));
    // A user's own setting is kept, either way.
    run("GLIBC_TUNABLES=glibc.malloc.hugetlb=0", on);
    CHECK_FALSE(on);
    run("GLIBC_TUNABLES=glibc.malloc.hugetlb=1", on);
    CHECK(on == glibc);
    // Under valgrind (seen by its preloaded library) it says how to follow into the tool.
    const Run valgrind = run("LD_PRELOAD=/nonexistent/vgpreload_core-amd64-linux.so", on);
    CHECK_THAT(valgrind.err, Contains("valgrind") && Contains("dexelmill-core"));
    // Without the tool beside it, the launcher says which file it could not start.
    fs::copy_file(DEXELMILL_CLI_PATH, cli.dir() / "dexelmill");
    const Run alone = cli.runIn("./dexelmill --version");
    CHECK(alone.code == 1);
    CHECK_THAT(alone.err, Contains("cannot start") && Contains((cli.dir() / "dexelmill-core").string()));
}

TEST_CASE("under an address-space limit a program's moves stop at the reader's limit, not the allocator's",
          "[cli][memory][errors]") {
#if defined(__SANITIZE_ADDRESS__)
    // AddressSanitizer reserves terabytes of address space for its shadow at start.
    SUCCEED("skipped: an AddressSanitizer build cannot start under ulimit -v");
#else
    const Cli cli("address_space");
    // A loop that never ends makes moves until a limit stops it. Under ulimit -v the process's
    // stacks, allocator arenas and libraries count too, beyond its resident memory.
    cli.file("loop.ngc", "G21 G90\n#1 = 1\no100 do\nG1 X#1 Y0 Z0 F100\n#1 = [0 - #1]\no100 while [1 GT 0]\nM2\n");
    for (const char* limit : {"600000", "1500000"}) {
        INFO("ulimit -v " << limit);
        const Run r = cli.runIn(std::string("ulimit -v ") + limit + " && '" + DEXELMILL_CLI_PATH + "' info loop.ngc");
        CHECK(r.code == 1);
        CHECK_THAT(r.err, Contains("loop.ngc:4:") && Contains("program makes more than") &&
                              Contains("the address-space limit (ulimit -v)"));
        CHECK_THAT(r.err, !Contains("out of memory"));
    }
#endif
}

TEST_CASE("a VDB cut short is refused at its first short read wherever a level set is read", "[cli][errors]") {
#if defined(__SANITIZE_ADDRESS__)
    SUCCEED("skipped: an AddressSanitizer build cannot start under ulimit -v");
#else
    const Cli cli("truncated_vdb");
    cli.file("slot.ngc", "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\nG0 Z5\n");
    cli.file("box.stl", boxStl({-5, -5, -3}, {15, 5, 0}));
    REQUIRE(cli("simulate slot.ngc --stock box:-5,-5,-3,15,5,0 --tool flat:d=2 --resolution 0.5 --vdb part.vdb -q")
                .code == 0);
    REQUIRE(fs::file_size(cli.dir() / "part.vdb") > 3000);
    // Cut there, OpenVDB's own reader took 2 GB and printed a 540 MB map name in its error.
    REQUIRE(cli.runIn("head -c 3000 part.vdb > cut.vdb").code == 0);
    for (const char* args : {"info cut.vdb", "compare cut.vdb box.stl", "compare box.stl cut.vdb",
                             "simulate slot.ngc --tool flat:d=2 --stock cut.vdb",
                             "simulate slot.ngc --tool flat:d=2 --design cut.vdb"}) {
        INFO(args);
        const Run r = cli.runIn(std::string("ulimit -v 1500000 && '") + DEXELMILL_CLI_PATH + "' " + args);
        CHECK(r.code == 1);
        CHECK_THAT(r.err, StartsWith("dexelmill: error: 'cut.vdb': not a complete OpenVDB file"));
        CHECK(r.err.size() < 200);
    }
#endif
}

TEST_CASE("a successful run writes every output and a one-line summary in mm", "[cli]") {
    const Cli cli("success");
    cli.file("slot.ngc", "G21 G90\nT1 M6\nG0 X5 Y15 Z15\nG1 Z7 F100\nG1 X35\nG0 Z15\nM30\n");
    const Run r = cli("simulate slot.ngc --stock box:0,0,0,40,30,10 --tool 1=flat:d=6 --resolution 0.5 "
                      "-o part.ply --vdb part.vdb --png part.png --report report.json --quiet");
    CHECK(r.code == 0);
    CHECK_THAT(r.out, Contains("mm^3") && Contains("closed"));
    // Counts of one are singular: the slot's two feed moves and its retract, one tool change. The
    // first rapid, from a start not given, only places the tool.
    CHECK_THAT(r.out, StartsWith("dexelmill: 3 moves (1 more not simulated: unknown position), 1 tool change; ") &&
                          Contains(" 0 collisions, "));
    CHECK(r.err.empty());  // --quiet
    for (const char* f : {"part.ply", "part.vdb", "part.png", "report.json"}) {
        INFO(f);
        CHECK(fs::file_size(cli.dir() / f) > 100);
    }
    const Run info = cli("info part.vdb");
    CHECK(info.code == 0);
    CHECK_THAT(info.out, Contains("level set") && Contains("0.5 mm"));
    // Refinement: its figures in the report, and the same part.
    const Run refined = cli("simulate slot.ngc --stock box:0,0,0,40,30,10 --tool 1=flat:d=6 --resolution 0.5 "
                            "--refine 1 --report refined.json --quiet");
    CHECK(refined.code == 0);
    const std::string report = slurp(cli.dir() / "refined.json");
    CHECK_THAT(report, Contains("\"refine\"") && Contains("\"points_tested\"") && Contains("\"edges_split\""));
    const Run prog = cli("info slot.ngc");
    CHECK(prog.code == 0);
    CHECK_THAT(prog.out, Contains("moves") && Contains("tool changes") && Contains("0 3+2 (fixed, tilted), 0 simultaneous"));
    cli.file("turn.apt", "MULTAX\nCUTTER/10\nFROM/0,0,0,0,0,1\nGOTO/40,0,0,0.5,0,0.8660254\nGOTO/0,0,0\nFINI\n");
    const Run turning = cli("info turn.apt");
    CHECK(turning.code == 0);
    CHECK_THAT(turning.out, Contains("0 3-axis (+z), 1 3+2 (fixed, tilted), 1 simultaneous multi-axis"));
    // A 4-axis program that never names Y, as UGS's rotation.ngc: info takes --start as simulate
    // does, and without it counts only the moves made once X, Y and Z are known.
    cli.file("wrap.ngc", "G21 G90\nG0 X0 Z25 A0\nG1 X10 Z19 A30\nG1 X20 A90\nM2\n");
    const Run unplaced = cli("info wrap.ngc --machine xyza");
    CHECK(unplaced.code == 0);
    CHECK_THAT(unplaced.out, Contains("moves          0 (0 rapid)") && Contains("start position is unknown"));
    const Run placed = cli("info wrap.ngc --machine xyza --start 0,0,0");
    CHECK(placed.code == 0);
    CHECK_THAT(placed.out, Contains("moves          3 (1 rapid)") && Contains("1 3-axis (+z), 0 3+2 (fixed, tilted), 2 simultaneous") &&
                               Contains("rotary range   A 0 .. 90 degrees"));
    const Run badStart = cli("info wrap.ngc --machine xyza --start 0,0");
    CHECK(badStart.code == 2);
    CHECK_THAT(badStart.err, Contains("--start takes X,Y,Z (mm)") && Contains("dexelmill info --help"));
    // Checked for any file, a level set's too.
    CHECK(cli("info part.vdb --start here").code == 2);
    const Run turned = cli("simulate turn.apt --stock box:-10,-10,-10,50,10,0 --turn-tolerance 0.001 --quiet");
    CHECK(turned.code == 0);
    const Run badTolerance = cli("simulate turn.apt --stock box:-10,-10,-10,50,10,0 --turn-tolerance 0 --quiet");
    CHECK(badTolerance.code != 0);
    CHECK_THAT(badTolerance.err, Contains("--turn-tolerance") && Contains("positive"));
    // Finer than the stock keeps: refused at once, where it would have run for hours.
    const Run tooFine = cli("simulate turn.apt --stock box:-10,-10,-10,50,10,0 --turn-tolerance 1e-9 --quiet");
    CHECK(tooFine.code == 2);
    CHECK_THAT(tooFine.err, Contains("--turn-tolerance: 1e-09 mm is finer than the stock keeps") && Contains("1e-06 mm or more"));
    // So coarse that a turning move would be swept with one axis: refused too.
    const Run tooCoarse = cli("simulate turn.apt --stock box:-10,-10,-10,50,10,0 --turn-tolerance 1e300 --quiet");
    CHECK(tooCoarse.code == 2);
    CHECK_THAT(tooCoarse.err, Contains("--turn-tolerance: 1e+300 mm") && Contains("0.1 mm or less"));
}

TEST_CASE("outputs on /dev/null, /dev/stdout or a pipe are written there whatever their names", "[cli]") {
    const Cli cli("device_outputs");
    cli.file("slot.ngc", "G21 G90\nT1 M6\nG0 X5 Y15 Z15\nG1 Z7 F100\nG1 X35\nG0 Z15\nM30\n");
    cli.file("design.stl", boxStl({0, 0, 0}, {40, 30, 7}));
    const std::string job = std::string("'") + DEXELMILL_CLI_PATH +
                            "' simulate slot.ngc --stock box:0,0,0,40,30,10 --tool 1=flat:d=6 --resolution 0.5 --quiet";
    // Every output of a run on /dev/null: none is refused for its name, nor as the same file as another.
    Run r = cli.runIn(job + " --design design.stl -o /dev/null --vdb /dev/null --png /dev/null --report /dev/null "
                            "--gouge-csv /dev/null --deviation-ply /dev/null");
    CHECK(r.code == 0);
    CHECK_THAT(r.out, StartsWith("dexelmill: 3 moves"));
    // The mesh down a pipe (binary STL where the name has no mesh extension) is the file -o writes.
    REQUIRE(cli.runIn(job + " -o part.stl").code == 0);
    r = cli.runIn("{ " + job + " -o /dev/stdout | cat > piped.stl; }");
    CHECK(slurp(cli.dir() / "piped.stl") == slurp(cli.dir() / "part.stl"));
    // The summary leaves a pipe or a file that stdout shares with an output to it: it goes to stderr.
    CHECK_THAT(r.err, StartsWith("dexelmill: 3 moves"));
    r = cli.runIn("{ " + job + " --report /dev/stdout | cat > piped.json; }");
    CHECK(nlohmann::json::parse(slurp(cli.dir() / "piped.json"))["moves"] == 3);
    CHECK_THAT(r.err, StartsWith("dexelmill: 3 moves"));
    r = cli.runIn(job + " --report /dev/stdout");  // stdout is out.txt, a regular file
    CHECK(r.code == 0);
    CHECK(nlohmann::json::parse(r.out)["moves"] == 3);
    // A level set down a pipe, where no offsets can be written back, reads back.
    r = cli.runIn("{ " + job + " --vdb /dev/stdout | cat > piped.vdb; }");
    const Run info = cli("info piped.vdb");
    CHECK(info.code == 0);
    CHECK_THAT(info.out, Contains("level set") && Contains("0.5 mm"));
    // compare's report and table likewise.
    r = cli.runIn("{ '" + std::string(DEXELMILL_CLI_PATH) + "' compare part.stl design.stl --report /dev/stdout | cat > "
                  "compare.json; }");
    CHECK(nlohmann::json::parse(slurp(cli.dir() / "compare.json")).contains("surface"));
    CHECK_THAT(r.err, Contains("deviation (mm)"));
}

TEST_CASE("a gouge and a collision carry one move number on the console, in the CSV and the report", "[cli]") {
    const Cli cli("move_numbers");
    // The design is the stock's lower half, z -10 .. -5. Line 3 only sets the start position; the
    // moves are lines 4 to 8, counted from 1: line 7, a rapid through the stock at z = -6, is
    // move 4, and cuts 1 mm into the design.
    cli.file("design.stl", boxStl({0, 0, -10}, {40, 30, -5}));
    cli.file("slot.ngc", "G21 G90\nT1 M6\nG0 X-5 Y15 Z5\nG1 Z-2 F300\nG1 X45\nG0 Z-6\nG0 X-5\nG0 Z5\nM30\n");
    const Run r = cli("simulate slot.ngc --stock box:0,0,-10,40,30,0 --tool 1=flat:d=6 --resolution 0.5 "
                      "--design design.stl --gouge-csv gouges.csv --report report.json");
    REQUIRE(r.code == 0);
    CHECK_THAT(r.err, Contains("slot.ngc:7: gouge: rapid move 4 (T1) cuts 1 mm") &&
                          Contains("slot.ngc:7: collision: rapid move 4 removes"));
    const std::string csv = slurp(cli.dir() / "gouges.csv");
    CHECK_THAT(csv, StartsWith("move,file,line,") && Contains("\n4,\"slot.ngc\",7,1,1.000000,"));
    const nlohmann::json j = nlohmann::json::parse(slurp(cli.dir() / "report.json"));
    REQUIRE(j["design"]["gouges"].size() == 1);
    CHECK(j["design"]["gouges"][0]["move"] == 4);
    bool rapid = false;
    for (const auto& c : j["collisions"])
        if (c["kind"] == "rapid") {
            rapid = true;
            CHECK(c["move"] == 4);
            CHECK(c["line"] == 7);
        }
    CHECK(rapid);
    // Tolerances of a hundredth of a micrometre print as decimals, in the summary as in the lines
    // above it, never with an exponent ("1e-05").
    const Run fine = cli("simulate slot.ngc --stock box:0,0,-10,40,30,0 --tool 1=flat:d=6 --resolution 0.5 "
                         "--design design.stl --gouge-tolerance 0.00001 --excess-tolerance 0.00001");
    REQUIRE(fine.code == 0);
    CHECK_THAT(fine.out + fine.err, Contains("tolerance 0.00001 mm"));
    CHECK_FALSE(std::regex_search(fine.out + fine.err, std::regex("[0-9]e[-+]?[0-9]")));
}

TEST_CASE("a study writes its table, CSV, plot and deviation meshes", "[cli][study]") {
    const Cli cli("study");
    const Run r = cli("study --case tilted-slot --resolutions 2,1,2 --families z,xyz,zyx --csv s.csv --plot s.png "
                      "--ply-deviation dev --surface-points 500 --samples 2000");
    REQUIRE(r.code == 0);
    CHECK_THAT(r.err, Contains("--resolutions lists 2 mm more than once; it runs once") &&
                          Contains("--families lists xyz more than once; it runs once"));
    CHECK_THAT(r.out, Contains("inner_max") && Contains("reference volume") && Contains("deviations in mm"));
    // One header and one row per (spacing, family set): the repeated spacing and set count once.
    const std::string csv = slurp(cli.dir() / "s.csv");
    CHECK(std::count(csv.begin(), csv.end(), '\n') == 5);
    CHECK_THAT(csv, Contains("h_mm,families") && Contains("\n2,z,") && Contains("\n1,xyz,"));
    const std::string png = slurp(cli.dir() / "s.png");
    CHECK(png.substr(1, 3) == "PNG");
    int plys = 0;
    for (const auto& e : fs::directory_iterator(cli.dir() / "dev")) {
        INFO(e.path());
        const std::string ply = slurp(e.path());
        REQUIRE(ply.rfind("ply\nformat binary_little_endian 1.0\n", 0) == 0);
        ++plys;
        // Coloured as compare colours: red where the model lacks material (a negative distance,
        // as a gouge), blue where it holds more, with no tolerance between; the distance beside
        // the colour.
        const std::size_t vertices = std::stoul(ply.substr(ply.find("element vertex ") + 15));
        REQUIRE(ply.find("property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float "
                         "deviation_mm\n") != std::string::npos);
        const std::size_t body = ply.find("end_header\n") + 11;
        std::size_t reddish = 0, bluish = 0;
        for (std::size_t v = 0; v < vertices; ++v) {
            const char* at = ply.data() + body + v * (12 + 3 + 4);
            const auto r = std::uint8_t(at[12]), b = std::uint8_t(at[14]);
            float d;
            std::memcpy(&d, at + 15, 4);
            if (d < 0.0f) {
                CHECK(r > b);
                ++reddish;
            }
            if (d > 0.0f) {
                CHECK(b > r);
                ++bluish;
            }
        }
        CHECK(reddish > 0);
        CHECK(bluish > 0);
    }
    CHECK(plys == 4);
}

TEST_CASE("a study refuses a stock it cannot measure against", "[cli][study][errors]") {
    const Cli cli("study_stock");
    cli.file("wedge.stl", "solid w\nendsolid w\n");
    const Run r = cli("study --case v-carve --stock wedge.stl");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("wedge.stl") && Contains("box"));
}

TEST_CASE("a program with no known move and no stock says why it made none", "[cli][errors]") {
    const Cli cli("no_moves");
    // Wholly incremental from an unknown start: no move is known, so no stock can be guessed, and
    // the error carries the reader's warning, which says what is missing.
    cli.file("g91.ngc", "G21 G91\nG1 X5 Y5 Z-1 F100\nG1 X10\nM30\n");
    const Run r = cli("simulate g91.ngc --tool flat:d=6 -o part.stl");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("no moves to guess one from, as it never gives the position it starts from; use "
                               "--start X,Y,Z") &&
                          Contains("--stock (the program's warning: g91.ngc:2:") && Contains("unknown"));
    // Not the F word's warning, which comes first but says nothing of why no move was made.
    CHECK_THAT(r.err, !Contains("feed rate"));
    CHECK_FALSE(fs::exists(cli.dir() / "part.stl"));
    // Given the start, the same program's moves are known and make the stock's guess.
    const Run started = cli("simulate g91.ngc --tool flat:d=6 --start 0,0,0 -o part.stl");
    CHECK(started.code == 0);
    CHECK(fs::exists(cli.dir() / "part.stl"));
}

TEST_CASE("a program with no move for another reason is not told to give a start", "[cli][errors]") {
    const Cli cli("no_moves_other");
    // An unknown M-code comes first and says "unknown", but the moves are missing because the
    // program makes none: --start would not help.
    cli.file("empty.ngc", "G21 G90\nM77\nM30\n");
    const Run r = cli("simulate empty.ngc --tool flat:d=6 -o part.stl");
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Contains("no moves to guess one from; use --stock"));
    CHECK_THAT(r.err, !Contains("--start"));
}

TEST_CASE("a note is printed and counted as a note, a warning as a warning", "[cli]") {
    const Cli cli("notes");
    // The first move's unknown start, 24 M-codes the interpreter does not know, each a warning of
    // its own place, the feed rate missing, and an M99 in the main program, a note: the console
    // prints 20 and counts the rest by kind.
    std::string program = "G21 G90\nG0 X5 Y15 Z15\n";
    for (int k = 0; k < 24; ++k) program += "G1 X" + std::to_string(5 + k) + " Z7 M" + std::to_string(110 + k) + "\n";
    program += "M99\n";
    cli.file("p.ngc", program);
    const Run r = cli("simulate p.ngc --stock box:0,0,0,40,30,10 --tool flat:d=6 --resolution 1 --report r.json");
    CHECK(r.code == 0);
    CHECK_THAT(r.err, Contains("p.ngc:3:10: warning: unknown M-code M110 ignored\n"));
    CHECK_THAT(r.err, Contains("\ndexelmill: 6 more warnings and 1 more note in r.json\n"));
    CHECK_THAT(r.out, Contains(" 26 warnings, 1 note; "));
    const nlohmann::json report = nlohmann::json::parse(slurp(cli.dir() / "r.json"));
    REQUIRE(report["warnings"].size() == 27);
    CHECK(report["warnings"][0]["severity"] == "warning");
    CHECK(report["warnings"][26]["message"] == "M99 in the main program ends it");
    CHECK(report["warnings"][26]["severity"] == "note");
    // info shows the first 10 and counts the rest by kind too.
    const Run listed = cli("info p.ngc");
    CHECK(listed.code == 0);
    CHECK_THAT(listed.out, Contains("warnings       26\nnotes          1\n") &&
                               Contains("  ... and 16 more warnings and 1 more note ('simulate' prints them all)\n"));
    // Within the first 20, the note is printed as one.
    cli.file("short.ngc", "G21 G90\nG0 X5 Y15 Z15\nG1 Z7 F100\nM99\n");
    const Run shortRun = cli("simulate short.ngc --stock box:0,0,0,40,30,10 --tool flat:d=6 --resolution 1");
    CHECK(shortRun.code == 0);
    CHECK_THAT(shortRun.err, Contains("short.ngc:4: note: M99 in the main program ends it\n"));
    CHECK_THAT(shortRun.out, Contains(" 2 warnings, 1 note; "));
    const Run info = cli("info short.ngc");
    CHECK(info.code == 0);
    CHECK_THAT(info.out, Contains("warnings       2\nnotes          1\n") &&
                             Contains("short.ngc:4: note: M99 in the main program ends it"));
}

TEST_CASE("diagnostics left out of a listing are counted by the kinds left out", "[cli]") {
    const Cli cli("notes_only_hidden");
    // Two warnings come first (the first move's unknown start, the feed rate), then 21 notes, one
    // for each subroutine read from a file of its own: the notes fill every place the listings
    // leave out, and no "0 more warnings" is printed.
    std::string program = "G21 G90\nG0 X5 Y15 Z15\nG1 Z7 F100\n";
    for (int k = 0; k < 21; ++k) {
        const std::string name = "s" + std::to_string(k);
        cli.file(name + ".ngc", "o<" + name + "> sub\nG1 X" + std::to_string(6 + k) + "\no<" + name + "> endsub\n");
        program += "o<" + name + "> call\n";
    }
    cli.file("p.ngc", program + "M2\n");
    const Run r = cli("simulate p.ngc --stock box:0,0,0,40,30,10 --tool flat:d=6 --resolution 1");
    CHECK(r.code == 0);
    CHECK_THAT(r.out, Contains(" 2 warnings, 21 notes; "));
    CHECK_THAT(r.err, Contains("\ndexelmill: 3 more notes\n") && !Contains("more warning"));
    const Run listed = cli("info p.ngc");
    CHECK(listed.code == 0);
    CHECK_THAT(listed.out, Contains("  ... and 13 more notes ('simulate' prints them all)\n") && !Contains("more warning"));
}
