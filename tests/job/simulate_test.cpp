// The main job end to end through the library: volumes against analytic values, report fields,
// failures that leave existing files alone.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "dexelmill/error.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/tool/builders.h"
#include "support/scratch.h"
#include "support/slot_job.h"

using namespace dexelmill;
namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;

fs::path scratch(const std::string& name) { return testing::scratchFolder("dexelmill_test_", name); }

std::string write(const fs::path& p, const std::string& text) {
    std::ofstream(p) << text;
    return p.string();
}

std::string read(const fs::path& p) {
    std::ifstream in(p);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

/// A slot 3 mm deep and 30 mm long with a D6 flat end mill: volume 3 (30 * 6 + pi * 9).
const char* kSlot =
    "G21 G90 G17\n"
    "T1 M6\n"
    "G0 X5 Y15 Z15\n"
    "G1 Z7 F100\n"
    "G1 X35\n"
    "G0 Z15\n"
    "M30\n";
const double kSlotVolume = 3 * (30 * 6 + kPi * 9);

/// kSlot, written in `dir`, on a 40 x 30 x 10 mm block with a flat D6 for every tool number.
SimulateOptions slotJob(const fs::path& dir) {
    SimulateOptions o;
    o.inputs = {write(dir / "slot.ngc", kSlot)};
    o.stockBox = Box{Vec3(0.0), Vec3(40, 30, 10)};
    o.defaultTool = flatEndMill(6, {20, 40});
    return o;
}

/// A project in `dir` that runs its `own.ngc` with a flat D6 as tool 1 on a 40 x 30 x 10 mm
/// block, its JSON members `resolution` (each with its comma) first.
std::string blockProject(const fs::path& dir, const std::string& resolution) {
    return write(dir / "p.camotics", "{" + resolution + R"(
      "tools": {"1": {"units": "metric", "shape": "cylindrical", "length": 20, "diameter": 6}},
      "workpiece": {"automatic": false, "bounds": {"min": [0, 0, 0], "max": [40, 30, 10]}},
      "files": ["own.ngc"]
    })");
}

}  // namespace

TEST_CASE("a collision above the flutes names the holder where the tool has one", "[job]") {
    // kSlot feeds at a tip height of 7 in a block 10 high: flutes 2 mm long leave the top 1 mm to
    // what is above them, a shank alone or a shank of 0.5 mm under a holder D20. The plunge's
    // flutes clear a hole as wide as the shank before the shank gets there, but not the holder's;
    // along the slot the shank meets its 0.5 mm and the holder the top 0.5 mm.
    const fs::path dir = scratch("holder");
    for (const bool holder : {false, true}) {
        SimulateOptions o = slotJob(dir);
        const Tool tool = flatEndMill(6, {2, holder ? 2.5 : 40.0});
        o.defaultTool = holder ? withHolder(tool, 20, 30) : tool;
        o.resolution = 0.5;
        const SimulateReport r = simulate(o);
        INFO("holder " << holder);
        std::vector<std::pair<int, std::string>> seen;
        for (const ReportCollision& c : r.collisions) seen.emplace_back(c.where.line, c.kind);
        using Seen = std::vector<std::pair<int, std::string>>;
        CHECK(seen == (holder ? Seen{{4, "holder"}, {5, "shank"}, {5, "holder"}} : Seen{{5, "shank"}}));
        if (!holder || seen.size() != 3) continue;
        // By hand, layers 0.5 mm thick. The plunge at x = 5: the holder's disk (radius 10) within
        // the block, less the circular segment past x = 0 (100 acos(1/2) - 5 sqrt(75)), less the
        // flutes' hole (radius 3). The slot to x = 35: the shank's strip 30 x 6 (its end's half
        // disk makes up for the start's, which the plunge took); the holder's strip 30 x 20 and its
        // end's half disk within x <= 40 (the half disk less the same segment), less the start's
        // half disk, which the plunge took: the strip less the segment.
        const double segment = 100.0 * std::acos(0.5) - 5.0 * std::sqrt(75.0), half = kPi * 50.0;
        CHECK(r.collisions[0].volumeMm3 == Approx(0.5 * (2.0 * half - segment - kPi * 9.0)).epsilon(0.01));
        CHECK(r.collisions[1].volumeMm3 == Approx(0.5 * 30.0 * 6.0).epsilon(0.01));
        CHECK(r.collisions[2].volumeMm3 == Approx(0.5 * (30.0 * 20.0 - segment)).epsilon(0.01));
    }
}

TEST_CASE("a slot removes its analytic volume and the report says so", "[job]") {
    const fs::path dir = scratch("slot");
    SimulateOptions o;
    o.inputs = {write(dir / "slot.ngc", kSlot)};
    o.stockBox = Box{Vec3(0.0), Vec3(40, 30, 10)};
    o.tools.emplace(1, flatEndMill(6, {20, 40}));
    o.resolution = 0.25;
    o.meshPath = (dir / "part.stl").string();
    o.reportPath = (dir / "report.json").string();
    const SimulateReport r = simulate(o);
    CHECK(r.removedVolumeMm3 == Approx(kSlotVolume).epsilon(0.01));
    CHECK(r.stockVolumeMm3 == Approx(40 * 30 * 10));
    CHECK(r.collisions.empty());
    CHECK(r.meshClosed);
    CHECK(r.meshVolumeMm3 == Approx(r.finalVolumeMm3).epsilon(0.005));
    CHECK(r.lattice == std::array<int, 3>{160, 120, 40});
    CHECK(r.dexels[2] == std::size_t(160 * 120));
    for (int a = 0; a < 3; ++a) {
        REQUIRE(r.familyVolumesMm3[a]);
        CHECK(*r.familyVolumesMm3[a] == Approx(40 * 30 * 10 - kSlotVolume).epsilon(0.001));
    }
    CHECK(r.toolChanges == 1);
    CHECK(r.rapids >= 1);

    const nlohmann::json j = nlohmann::json::parse(read(dir / "report.json"));
    for (const char* key : {"version", "inputs", "resolution_mm", "families", "moves", "moves_not_simulated",
                            "rapids", "tool_changes", "lattice", "dexels", "stock_volume_mm3", "final_volume_mm3",
                            "removed_volume_mm3", "family_volumes_mm3", "finer_than_lattice", "collisions", "warnings",
                            "mesh", "timing_s", "peak_memory_mb"})
        CHECK(j.contains(key));
    // Nothing the lattice cannot show: the slot's walls and floor lie between lattice planes.
    CHECK(r.fineFeatures.material.count == 0);
    CHECK(r.fineFeatures.gaps.count == 0);
    CHECK(j["removed_volume_mm3"].get<double>() == Approx(kSlotVolume).epsilon(0.01));
    CHECK(j["mesh"]["closed"].get<bool>());
    // The block's bottom, which no move reaches, is (160 - 1) x (120 - 1) plain cells (two
    // triangles each, no patch vertex); its sides and the slot's floor add more.
    CHECK(j["mesh"]["dexel_mesher"]["plain_cells"].get<std::size_t>() == r.plainCells);
    CHECK(j["mesh"]["dexel_mesher"]["patch_pairs_left_crossing"].get<std::size_t>() ==
          r.patchPairsLeftCrossing);
    CHECK(r.plainCells > std::size_t(159 * 119));
    CHECK(j["lattice"]["nx"].get<int>() == 160);
    CHECK(j["family_volumes_mm3"].contains("y"));
    for (const char* key : {"parse", "cut", "rebuild", "mesh", "write", "total"}) CHECK(j["timing_s"].contains(key));
    // The F word is reported, not dropped.
    bool feedWarned = false;
    for (const auto& w : j["warnings"]) feedWarned = feedWarned || w.value("line", 0) == 4;
    CHECK(feedWarned);
    CHECK(fs::file_size(dir / "part.stl") == 84 + 50 * r.meshTriangles);
}

TEST_CASE("the report gives a warning's file, line and column only where it has them", "[job]") {
    SimulateReport r;
    r.warnings = {ReportWarning{SourceLocation{"", 0, 0}, "the stock is the program's extent"},
                  ReportWarning{SourceLocation{"p.ngc", 0, 0}, "the program makes no moves"},
                  ReportWarning{SourceLocation{"p.ngc", 4, 0}, "F100 is ignored"},
                  ReportWarning{SourceLocation{"p.ngc", 6, 9}, "M8 is ignored"},
                  ReportWarning{SourceLocation{"p.ngc", 7, 0}, "M99 in the main program ends it",
                                Diagnostic::Severity::Note}};
    const nlohmann::json j = nlohmann::json::parse(reportJson(r));
    // The format number of the report's keys, as the README gives it.
    CHECK(j["format"] == 1);
    REQUIRE(j["warnings"].size() == 5);
    const nlohmann::json& whole = j["warnings"][0];
    CHECK_FALSE(whole.contains("file"));
    CHECK_FALSE(whole.contains("line"));
    CHECK(whole["message"] == "the stock is the program's extent");
    const nlohmann::json& file = j["warnings"][1];
    CHECK(file["file"] == "p.ngc");
    CHECK_FALSE(file.contains("line"));
    const nlohmann::json& line = j["warnings"][2];
    CHECK(line["file"] == "p.ngc");
    CHECK(line["line"] == 4);
    CHECK_FALSE(line.contains("column"));
    CHECK(line["message"] == "F100 is ignored");
    const nlohmann::json& column = j["warnings"][3];
    CHECK(column["line"] == 6);
    CHECK(column["column"] == 9);
    CHECK(column["severity"] == "warning");
    CHECK(j["warnings"][4]["severity"] == "note");
}

TEST_CASE("simulate: a wall thinner than the spacing is reported and meshed", "[job][fine]") {
    // Two slots 6 mm wide along y at x = 10 and 16.3 leave a wall 0.3 mm thick between x = 13 and
    // 13.3, where the lattice (spacing 1) has planes at 12.5 and 13.5: the level set cannot show
    // it, the mesh shows it from the dexels.
    const fs::path dir = scratch("thin-wall");
    SimulateOptions o;
    o.inputs = {write(dir / "walls.ngc", "G21 G90\nG0 X10 Y5 Z15\nG1 Z7 F100\nG1 Y25\nG0 Z15\nG0 X16.3 Y5\n"
                                         "G1 Z7\nG1 Y25\nG0 Z15\nM30\n")};
    o.stockBox = Box{Vec3(0.0), Vec3(40, 30, 10)};
    o.defaultTool = flatEndMill(6, {20, 40});
    o.resolution = 1.0;
    o.reportPath = (dir / "report.json").string();
    const SimulateReport r = simulate(o);
    const FineStretches& wall = r.fineFeatures.material;
    // Every x-dexel through the wall's straight part (y 5.5 to 24.5, z 7.5 to 9.5) at least.
    CHECK(wall.count >= std::size_t(20 * 3));
    CHECK(wall.widestMm >= 0.3);
    CHECK(wall.widestMm < 1.0);
    CHECK(wall.widestAt.x > 12.5);
    CHECK(wall.widestAt.x < 13.5);
    CHECK(r.fineFeatures.gaps.count == 0);
    bool warned = false;
    for (const ReportWarning& w : r.warnings)
        warned = warned || (w.message.find("material thinner than the lattice (walls, fins, ridge tops) is left out") != std::string::npos &&
                            w.message.find(std::to_string(wall.count) + " dexel stretches") != std::string::npos &&
                            w.message.find("in 1 place,") != std::string::npos &&
                            w.message.find("the mesh shows it") != std::string::npos);
    CHECK(warned);
    // The part: the block less two slots, each a 6 mm disc swept 20 mm, 3 mm deep. The wall's top
    // lies above the last lattice plane (z = 9.5), where no dexel crosses it: 0.5 mm of its height
    // is the mesher's estimate, at most 0.3 x 20 x 0.5 = 3 mm^3; without the wall the mesh would
    // lack 18 mm^3 and more.
    const double slot = (6.0 * 20.0 + M_PI * 9.0) * 3.0;
    CHECK(r.meshVolumeMm3 == Approx(40.0 * 30.0 * 10.0 - 2.0 * slot).margin(3.0));
    CHECK(r.meshClosed);
    CHECK(r.meshFoldedTriangles == 0);
    CHECK(r.splitEdges > 0);
    CHECK(r.splitEdgesDropped == 0);
    CHECK(r.meshRuns == 1);
    const nlohmann::json j = nlohmann::json::parse(read(dir / "report.json"));
    CHECK(j["mesh"]["dexel_mesher"]["runs"].get<int>() == 1);
    CHECK(j["finer_than_lattice"]["material"]["stretches"].get<std::size_t>() == wall.count);
    CHECK(j["finer_than_lattice"]["material"]["widest_mm"].get<double>() == wall.widestMm);
    CHECK(j["finer_than_lattice"]["gaps"]["stretches"].get<std::size_t>() == 0);
    // One place: the wall, between the slots.
    CHECK(j["finer_than_lattice"]["material"]["places"].get<std::size_t>() == 1);
    const auto& place = j["finer_than_lattice"]["material"]["regions"].at(0);
    CHECK(place["box_mm"]["min"][0].get<double>() > 12.9);
    CHECK(place["box_mm"]["max"][0].get<double>() < 13.5);
    CHECK(place["stretches"].get<std::size_t>() == wall.count);
}

TEST_CASE("the stock's volume is its box's at spacings that do not divide it", "[job]") {
    // 40 x 30 x 10 mm at 0.3 mm is 133.3 x 100 x 33.3 cells, at 0.7 mm 57.1 x 42.9 x 14.3 and at
    // 1.5 mm 26.7 x 20 x 6.7: every family must still measure 12,000 mm^3, the last lattice line
    // of each axis standing for the stock up to its face (each dexel's length is a float, within
    // 2^-24 of the box's). The slot's volume is the midpoint rule's across the dexels: within one
    // spacing of its outline (shorter than its 36 x 6 mm box's perimeter, 84 mm) times its depth.
    SimulateOptions o = slotJob(scratch("spacings"));
    for (const double h : {0.3, 0.7, 1.5}) {
        INFO("h = " << h);
        o.resolution = h;
        const SimulateReport r = simulate(o);
        CHECK(r.stockVolumeMm3 == Approx(40.0 * 30.0 * 10.0).epsilon(0x1p-23));
        for (const std::optional<double>& v : r.familyVolumesMm3) {
            REQUIRE(v);
            CHECK(*v + r.removedVolumeMm3 == Approx(40.0 * 30.0 * 10.0).margin(h * 2.0 * (36.0 + 6.0) * 3.0));
        }
        CHECK(r.removedVolumeMm3 == Approx(kSlotVolume).margin(h * 2.0 * (36.0 + 6.0) * 3.0));
    }
}

TEST_CASE("z-only and x-only stocks measure the same slot", "[job]") {
    SimulateOptions o = slotJob(scratch("families"));
    o.resolution = 0.25;
    for (const char* f : {"z", "x"}) {
        o.families = FamilySet::parse(f);
        const Simulation s = runSimulation(o);
        INFO(f);
        CHECK(s.report.removedVolumeMm3 == Approx(kSlotVolume).epsilon(0.01));
        CHECK(s.report.meshClosed);
        CHECK(s.report.dexels[f[0] == 'z' ? 0 : 2] == 0);
    }
}

TEST_CASE("a failed run leaves existing outputs untouched", "[job][errors]") {
    const fs::path dir = scratch("noclobber");
    const std::string out = write(dir / "part.obj", "keep me\n");
    const std::string report = write(dir / "report.json", "{\"old\": true}\n");
    SimulateOptions o;
    o.inputs = {write(dir / "bad.ngc", "G21\nG1 X1 Y2 Z3 F100\nG1 X1..5\n")};
    o.stockBox = Box{Vec3(0.0), Vec3(10.0)};
    o.defaultTool = flatEndMill(3);
    o.meshPath = out;
    o.reportPath = report;
    CHECK_THROWS_AS(simulate(o), ParseError);
    CHECK(read(out) == "keep me\n");
    CHECK(read(report) == "{\"old\": true}\n");
    // No temporary files are left behind either.
    std::size_t files = 0;
    for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
    CHECK(files == 3);
}

TEST_CASE("the job names what is missing or malformed", "[job][errors]") {
    const fs::path dir = scratch("errors");
    SimulateOptions o;
    o.inputs = {write(dir / "t2.ngc", "G21\nT2 M6\nG0 X0 Y0 Z5\nG1 X5\n")};
    o.stockBox = Box{Vec3(0.0), Vec3(10.0)};
    o.tools.emplace(1, flatEndMill(3));
    o.tools.emplace(3, flatEndMill(4));
    CHECK_THROWS_WITH(runSimulation(o), Catch::Matchers::Contains("t2.ngc:") && Catch::Matchers::Contains("T2") &&
                                            Catch::Matchers::Contains("--tool 2="));
    o.tools.emplace(2, flatEndMill(3));
    o.meshPath = (dir / "part.xyz").string();
    CHECK_THROWS_WITH(runSimulation(o), Catch::Matchers::Contains(".obj, .stl or .ply"));
    o.meshPath.clear();
    o.inputs = {(dir / "missing.ngc").string()};
    CHECK_THROWS_WITH(runSimulation(o), Catch::Matchers::Contains("missing.ngc"));
}

TEST_CASE("an undefined tool number takes the only tool defined, and no other", "[job][errors][degenerate]") {
    ToolTable defined;
    CHECK_FALSE(standInTool(defined).has_value());
    defined.emplace(7, flatEndMill(3));
    CHECK(standInTool(defined) == std::optional<int>(7));
    defined.emplace(2, flatEndMill(4));
    CHECK_FALSE(standInTool(defined).has_value());
}

TEST_CASE("a stock file keeps its solid: an open STL is refused, a VDB read back at its spacing keeps its dexels",
          "[job][errors][degenerate]") {
    const fs::path dir = scratch("stockfile");
    // A 20 x 20 x 15 mm block, x and y from -10 to 10 and z from -15 to 0, its faces' triangles
    // counter-clockwise seen from outside; the open one lacks a triangle of the top.
    std::string facets;
    const auto quad = [&](const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
        for (const auto& t : {std::array<Vec3, 3>{a, b, c}, std::array<Vec3, 3>{a, c, d}}) {
            facets += "facet normal 0 0 0\nouter loop\n";
            for (const Vec3& v : t)
                facets += "vertex " + std::to_string(v.x) + " " + std::to_string(v.y) + " " + std::to_string(v.z) + "\n";
            facets += "endloop\nendfacet\n";
        }
    };
    const double x0 = -10, x1 = 10, y0 = -10, y1 = 10, z0 = -15, z1 = 0;
    quad({x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0});  // bottom
    quad({x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1});  // front, y = y0
    quad({x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1});  // right
    quad({x1, y1, z0}, {x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1});  // back
    quad({x0, y1, z0}, {x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1});  // left
    const std::string sides = facets;
    quad({x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1});  // top
    const std::string closedStl = write(dir / "block.stl", "solid block\n" + facets + "endsolid block\n");
    const std::size_t lastFacet = facets.rfind("facet normal");
    const std::string openStl = write(dir / "open.stl", "solid open\n" + facets.substr(0, lastFacet) + "endsolid open\n");
    CHECK(sides.size() < lastFacet);

    SimulateOptions o;
    o.inputs = {write(dir / "far.ngc", "G21 G90\nG0 X100 Y100 Z100\nG0 X101\nM2\n")};
    o.defaultTool = flatEndMill(10);
    o.resolution = 0.25;
    o.stockFile = openStl;
    // Cast whole, the open block's lines through the missing triangle meet one face: before, the
    // z family lost them and the dexel mesher crashed on families that disagreed.
    CHECK_THROWS_WITH(runSimulation(o), Catch::Matchers::Contains("open.stl' is not closed"));

    o.stockFile = closedStl;
    o.vdbPath = (dir / "block.vdb").string();
    const SimulateReport fromStl = simulate(o);
    CHECK(fromStl.stockVolumeMm3 == Approx(20 * 20 * 15).epsilon(1e-6));
    // Read back at the spacing it was written with, the level set keeps its lattice: taken on the
    // material box instead, the lines on the block's faces lost a ring of dexels (2.5 %, 5850 mm^3).
    o.stockFile = o.vdbPath;
    o.vdbPath.clear();
    const SimulateReport fromVdb = simulate(o);
    CHECK(fromVdb.stockVolumeMm3 == Approx(20 * 20 * 15).epsilon(1e-3));
    for (int a = 0; a < 3; ++a) {
        REQUIRE(fromVdb.familyVolumesMm3[a]);
        CHECK(*fromVdb.familyVolumesMm3[a] == Approx(20 * 20 * 15).epsilon(1e-3));
    }
}

TEST_CASE("a --max-memory the process has spent before it starts is named, not blamed on the program",
          "[job][errors][memory]") {
    const fs::path dir = scratch("tinybudget");
    SimulateOptions o;
    o.inputs = {write(dir / "slot.ngc", kSlot)};
    o.stockBox = Box{Vec3(0.0), Vec3(40, 30, 10)};
    o.tools.emplace(1, flatEndMill(6, {20, 40}));
    // A test process holds more than a mebibyte before any job (its code and libraries alone).
    o.maxMemoryBytes = std::size_t(1) << 20;
    CHECK_THROWS_WITH(runSimulation(o), Catch::Matchers::Contains("the process holds before it reads the programs") &&
                                            Catch::Matchers::Contains("give a larger --max-memory"));
}

TEST_CASE("the default spacing is a round fraction of the stock", "[job]") {
    CHECK(chooseResolution(Box{Vec3(0.0), Vec3(1694, 890, 870)}) == Approx(2.0));
    CHECK(chooseResolution(Box{Vec3(0.0), Vec3(80, 80, 20)}) == Approx(0.2));
    CHECK(chooseResolution(Box{Vec3(0.0), Vec3(1000, 800, 440)}) == Approx(2.0));
    // A sheet: two cells across its 1 mm, not 1/400 of its 400 mm.
    CHECK(chooseResolution(Box{Vec3(0.0), Vec3(400, 400, 1)}) == Approx(0.5));
    CHECK(chooseResolution(Box{Vec3(0.0), Vec3(400, 400, 0.3)}) == Approx(0.1));
}

TEST_CASE("programs after a project replace its programs; its tools and stock stay", "[job]") {
    const fs::path dir = scratch("project");
    write(dir / "own.ngc", "G21 G90\nT1\nG0 X5 Y5 Z5\nG1 Z-1 F100\nG1 X15\n");
    const std::string other = write(dir / "other.ngc", kSlot);
    const std::string project = write(dir / "p.camotics", R"({
      "units": "metric",
      "resolution-mode": "manual", "resolution": 0.5,
      "tools": {"1": {"units": "metric", "shape": "cylindrical", "length": 20, "diameter": 6}},
      "workpiece": {"automatic": false, "bounds": {"min": [0, 0, 0], "max": [40, 30, 10]}},
      "files": ["own.ngc"]
    })");
    SimulateOptions o;
    o.inputs = {project, other};
    const SimulateReport r = runSimulation(o).report;
    CHECK(r.resolutionMm == 0.5);
    CHECK(r.stockVolumeMm3 == Approx(12000));
    CHECK(r.removedVolumeMm3 == Approx(kSlotVolume).epsilon(0.02));
}

TEST_CASE("a project's resolution mode computes the spacing from the stock, as CAMotics does", "[job]") {
    const fs::path dir = scratch("resolution_mode");
    write(dir / "own.ngc", "G21 G90\nT1\nG0 X5 Y5 Z5\nG1 Z-1 F100\nG1 X15\n");
    // A 40 x 30 x 10 mm block in the low mode: the cube root of 12,000 mm^3 over 1e5 cells.
    const double low = std::cbrt(12000.0 / 1e5);
    for (const char* stored : {"", R"("resolution": 0.493242,)", R"("resolution": 0.1,)"}) {
        INFO(stored);
        const std::string project = blockProject(dir, std::string(R"("resolution-mode": "low", )") + stored);
        SimulateOptions o;
        o.inputs = {project};
        const SimulateReport r = runSimulation(o).report;
        CHECK_FALSE(r.resolutionChosen);
        CHECK(r.resolutionMm == Approx(low).epsilon(1e-12));
        // Only a stored number that differs from the mode's is named, as the manual mode's.
        bool said = false;
        for (const ReportWarning& w : r.warnings)
            said = said || (w.where.file == project && w.message.find("manual mode only") != std::string::npos);
        CHECK(said == (std::string(stored).find("0.1,") != std::string::npos));
    }
}

TEST_CASE("a tool option the job cannot use, or that replaces the program's tool, is named", "[job]") {
    const fs::path dir = scratch("tool_options");
    const std::string program = write(dir / "p.ngc", "G21 G90\nT1 M6\nG0 X5 Y5 Z5\nG1 Z-1 F100\nG1 X15\n");
    const std::string project = write(dir / "p.camotics", R"({
      "resolution-mode": "manual", "resolution": 0.5,
      "tools": {"1": {"units": "metric", "shape": "cylindrical", "length": 20, "diameter": 6}},
      "workpiece": {"automatic": false, "bounds": {"min": [0, 0, -5], "max": [40, 30, 0]}},
      "files": ["p.ngc"]
    })");
    auto said = [](const SimulateReport& r, const char* text) {
        for (const ReportWarning& w : r.warnings)
            if (w.message.find(text) != std::string::npos) return true;
        return false;
    };
    SimulateOptions bare;
    bare.inputs = {project};
    bare.defaultTool = flatEndMill(10.0, {20.0, 30.0});
    const SimulateReport unused = runSimulation(bare).report;
    CHECK(said(unused, "--tool without a number (flat D10"));
    CHECK(said(unused, "is not used"));
    // The project's D6 cut the 1 mm deep slot: 10 mm long, 6 wide, with round ends.
    CHECK(unused.removedVolumeMm3 == Approx(10 * 6 + kPi * 9).epsilon(0.02));

    SimulateOptions numbered;
    numbered.inputs = {project};
    numbered.tools.insert_or_assign(1, flatEndMill(10.0, {20.0, 30.0}));
    const SimulateReport replaced = runSimulation(numbered).report;
    CHECK(said(replaced, "replaces the program's tool 1 (flat D6"));
    // What the run did in the program's stead: a note, not a warning.
    for (const ReportWarning& w : replaced.warnings)
        if (w.message.find("replaces the program's tool") != std::string::npos)
            CHECK(w.severity == Diagnostic::Severity::Note);
    CHECK(replaced.removedVolumeMm3 == Approx(10 * 10 + kPi * 25).epsilon(0.02));

    SimulateOptions after;
    after.inputs = {project, program};
    CHECK(said(runSimulation(after).report, "replace its own ("));

    // A numbered tool no move takes is named; so is a --start an APT file has no use for.
    SimulateOptions extra;
    extra.inputs = {program};
    extra.stockBox = Box{Vec3(0, 0, -5), Vec3(40, 30, 0)};
    extra.tools.emplace(1, flatEndMill(6.0, {20.0, 30.0}));
    extra.tools.emplace(5, flatEndMill(3.0, {20.0, 30.0}));
    const SimulateReport five = runSimulation(extra).report;
    CHECK(said(five, "--tool 5=... (flat D3"));
    CHECK(said(five, "no move cuts with tool 5"));
    CHECK_FALSE(said(five, "no move cuts with tool 1"));
    SimulateOptions apt;
    apt.inputs = {write(dir / "p.apt", "CUTTER/6\nFROM/5,5,5\nGOTO/5,5,-1\nGOTO/15,5,-1\n")};
    apt.stockBox = extra.stockBox;
    apt.startPosition = Vec3(0.0);
    CHECK(said(runSimulation(apt).report, "--start is not used: an APT CL file places the tool itself"));
}

TEST_CASE("the only tool defined cuts every undefined number, and is not called unused", "[job][degenerate]") {
    const fs::path dir = scratch("stand_in");
    auto said = [](const SimulateReport& r, const char* text) {
        for (const ReportWarning& w : r.warnings)
            if (w.message.find(text) != std::string::npos) return true;
        return false;
    };
    // Moves before any tool is selected (tool 0), then tool 5, which nobody defines: --tool 1 cuts
    // both. The slot is 1 mm deep, 10 mm long and 6 wide with round ends.
    SimulateOptions o;
    o.inputs = {write(dir / "p.ngc", "G21 G90\nG0 X5 Y5 Z5\nG1 Z-1 F100\nT5 M6\nG1 X15\n")};
    o.stockBox = Box{Vec3(0, 0, -5), Vec3(40, 30, 0)};
    o.resolution = 0.5;
    o.tools.emplace(1, flatEndMill(6.0, {20.0, 30.0}));
    const SimulateReport r = runSimulation(o).report;
    CHECK(said(r, "moves before any tool is selected; using the only tool defined, T1"));
    CHECK(said(r, "tool T5 is not defined; using the only tool defined, T1"));
    CHECK_FALSE(said(r, "is not used"));
    CHECK(r.removedVolumeMm3 == Approx(10 * 6 + kPi * 9).epsilon(0.02));
}

TEST_CASE("a stock guessed below z = 0 says where the cuts above it go", "[job]") {
    const fs::path dir = scratch("guessed_top");
    // Feed moves from z = 3 down to z = -2 and back: the stock's top is z = 0, the cuts' is z = 3.
    SimulateOptions o;
    o.inputs = {write(dir / "p.ngc", "G21 G90\nG0 X0 Y0 Z3\nG1 Z-2 F100\nG1 X20\nG1 Z3\nM30\n")};
    o.defaultTool = flatEndMill(4.0, {20.0, 30.0});
    o.resolution = 0.5;
    const SimulateReport r = runSimulation(o).report;
    CHECK(r.stockBox.hi.z == 0.0);
    bool said = false;
    for (const ReportWarning& w : r.warnings)
        said = said || w.message.find("its top at z = 0 mm, where the program's cuts go down from: the cuts above it, "
                                      "up to z = 3 mm, meet no stock") != std::string::npos;
    CHECK(said);
    // Cuts that stay below z = 0 leave no such words.
    o.inputs = {write(dir / "q.ngc", "G21 G90\nG0 X0 Y0 Z-1\nG1 Z-2 F100\nG1 X20\nM30\n")};
    for (const ReportWarning& w : runSimulation(o).report.warnings) CHECK(w.message.find("its top at") == std::string::npos);
}

TEST_CASE("a program without moves says so", "[job][errors]") {
    const fs::path dir = scratch("no_moves");
    for (const char* text : {"", "(only a comment)\n\n%\n", "G21 G90 M3 S1000\n"}) {
        INFO("'" << text << "'");
        SimulateOptions o;
        o.inputs = {write(dir / "p.ngc", text)};
        o.defaultTool = flatEndMill(3.0, {20.0, 30.0});
        o.stockBox = Box{Vec3(0.0), Vec3(10, 10, 5)};
        o.resolution = 0.5;
        const SimulateReport r = runSimulation(o).report;
        CHECK(r.moves == 0);
        bool said = false;
        for (const ReportWarning& w : r.warnings)
            said = said || (w.where.file == o.inputs[0] && w.message.find("no moves") != std::string::npos);
        CHECK(said);
    }
}

TEST_CASE("a move that turns the tool axis cuts what its poses reach, and nothing beyond",
          "[job][turning]") {
    const fs::path dir = scratch("turning");
    // A flat D10, 50 mm long overall, at tip height 0, fed along x while its axis turns from
    // (-0.5, 0, 0.866) through (0, 0, 1) to (0.5, 0, 0.866). Its top rim, at 50 cos t + 5 sin t for
    // a lean t, reaches sqrt(50^2 + 5^2) = 50.249 at t = 5.7 degrees, inside the turn (the ends
    // reach 45.8): a stock from z = 50.2 is within reach, one from 50.3 is not. Below, the flat
    // bottom tilted 30 degrees at either end reaches 5 sin 30 = 2.5 under the tip.
    auto program = [&](const char* kind) {
        return write(dir / "turn.apt", std::string("MULTAX\nCUTTER/10\nFROM/0,0,0,-0.5,0,0.8660254\n") + kind +
                                           "GOTO/40,0,0,0.5,0,0.8660254\nFINI\n");
    };
    auto run = [&](const char* kind, double lo, double hi) {
        SimulateOptions o;
        o.inputs = {program(kind)};
        o.stockBox = Box{Vec3(-20, -20, lo), Vec3(60, 20, hi)};
        o.resolution = 0.25;
        return runSimulation(o).report;
    };
    auto said = [](const SimulateReport& r, const std::string& what) {
        for (const ReportWarning& w : r.warnings)
            if (w.message.find(what) != std::string::npos && w.where.line >= 4) return true;
        return false;
    };
    using Catch::Matchers::Contains;
    SimulateReport r;
    REQUIRE_NOTHROW(r = run("", 50.2, 60));
    CHECK(r.removedVolumeMm3 > 0.0);
    REQUIRE_NOTHROW(r = run("", 50.3, 60));
    CHECK(r.removedVolumeMm3 == 0.0);
    REQUIRE_NOTHROW(r = run("", -10, -2.4));
    CHECK(r.removedVolumeMm3 > 0.0);
    REQUIRE_NOTHROW(r = run("", -10, -2.6));
    CHECK(r.removedVolumeMm3 == 0.0);
    // Refinement follows the turning sweep too (tests/refine: within its tolerance).
    {
        SimulateOptions o;
        o.inputs = {program("")};
        o.stockBox = Box{Vec3(-20, -20, -10), Vec3(60, 20, -2.4)};
        o.resolution = 0.5;
        o.refineRounds = 1;
        REQUIRE_NOTHROW(r = runSimulation(o).report);
        CHECK(r.refineRounds == 1);
        CHECK(r.refineQueries > 0);
        CHECK(r.meshClosed);
        CHECK(r.meshFoldedTriangles == 0);
    }
    // A rapid that turns is a reorientation on the machine's own path: swept with its end axis,
    // with a warning.
    REQUIRE_NOTHROW(r = run("RAPID\n", 40, 60));
    CHECK(said(r, "1 move turns the tool axis at rapid within reach"));
    // A machine's rotary rapid is not: the machine's law says where the tool goes, and the sweep
    // follows it. The A table turns the stock 45 degrees and back under a tool whose tip is 30 mm
    // from the A axis, within reach of the stock's box.
    {
        SimulateOptions o;
        o.inputs = {write(dir / "rotary.ngc", "G21 G90\nG0 X0 Y0 Z30 A0\nG0 A45\nG0 A0\nM30\n")};
        o.machine = "xyza";
        o.stockBox = Box{Vec3(-20, -20, -20), Vec3(20, 20, 0)};
        o.defaultTool = flatEndMill(6, {20, 40});
        o.resolution = 1.0;
        REQUIRE_NOTHROW(r = runSimulation(o).report);
        CHECK(r.moves == 2);
        for (const ReportWarning& w : r.warnings) CHECK_THAT(w.message, !Contains("at rapid within reach"));
    }

    // A head that turns in identity kinematics: B turning the tool about a pivot 40 mm above the
    // tip, joints still, moves the tool relative to the part exactly as a table B about the same
    // point (in the machine frame) turning the other way does. The two jobs run different laws
    // (heads carried with the joints, tables carrying the part) to the same swept volume.
    {
        const std::string head = write(dir / "head.json", R"({"name": "head", "axes": [
            {"letter": "B", "on": "head", "direction": [0, 1, 0], "pivot": [0, 0, 40]}]})");
        const std::string table = write(dir / "table.json", R"({"name": "table", "axes": [
            {"letter": "B", "on": "table", "direction": [0, 1, 0], "pivot": [0, 0, 40]}]})");
        auto swing = [&](const std::string& machine, const char* program) {
            SimulateOptions o;
            o.inputs = {write(dir / "swing.ngc", program)};
            o.machine = machine;
            o.stockBox = Box{Vec3(-30, -10, -5), Vec3(30, 10, 2)};
            o.defaultTool = flatEndMill(6, {20, 40});
            o.resolution = 0.5;
            return runSimulation(o).report;
        };
        SimulateReport h, t;
        REQUIRE_NOTHROW(h = swing(head, "G21 G90\nG0 X0 Y0 Z0 B-30\nG1 B30 F100\nM30\n"));
        REQUIRE_NOTHROW(t = swing(table, "G21 G90\nG0 X0 Y0 Z0 B30\nG1 B-30 F100\nM30\n"));
        // The tip swings on an arc of radius 40 from (-20, 0, 5.36) down to the origin and back.
        CHECK(h.removedVolumeMm3 > 100.0);
        // Both sweeps lie within the turn tolerance (1e-4 mm) of the same volume, whose surface in
        // the stock is well under 1,000 mm^2.
        CHECK(h.removedVolumeMm3 == Approx(t.removedVolumeMm3).margin(0.1));
        CHECK(h.meshClosed);
    }
    // Opposite axes: no great circle to turn on.
    {
        SimulateOptions o;
        o.inputs = {write(dir / "flip.apt", "MULTAX\nCUTTER/10\nFROM/0,0,100,0,0,1\nGOTO/0,0,100,0,0,-1\n")};
        o.stockBox = Box{Vec3(-20, -20, -20), Vec3(20, 20, 0)};
        o.resolution = 1.0;
        CHECK_THROWS_WITH(runSimulation(o), Contains("flip.apt:4:1: error") && Contains("opposite"));
    }
    // A turn too small to move any point of the tool by the sweep's accuracy is a fixed-axis move.
    {
        SimulateOptions o;
        o.inputs = {write(dir / "tiny.apt", "MULTAX\nCUTTER/10\nFROM/0,0,-1,0,0,1\nGOTO/10,0,-1,1E-9,0,1\n")};
        o.stockBox = Box{Vec3(-20, -20, -20), Vec3(20, 20, 0)};
        o.resolution = 1.0;
        REQUIRE_NOTHROW(r = runSimulation(o).report);
        CHECK(r.removedVolumeMm3 > 0.0);
    }
}

TEST_CASE("a project resolution that is not positive is replaced with a warning that says so", "[job][errors]") {
    const fs::path dir = scratch("bad_resolution");
    write(dir / "own.ngc", "G21 G90\nT1\nG0 X5 Y5 Z5\nG1 Z-1 F100\nG1 X15\n");
    for (const char* value : {"0", "-1"}) {
        INFO(value);
        const std::string project =
            blockProject(dir, std::string(R"("resolution-mode": "manual", "resolution": )") + value + ",");
        SimulateOptions o;
        o.inputs = {project};
        const SimulateReport r = runSimulation(o).report;
        CHECK(r.resolutionChosen);
        CHECK(r.resolutionMm == Approx(chooseResolution(Box{Vec3(0.0), Vec3(40, 30, 10)})));
        bool said = false;
        for (const ReportWarning& w : r.warnings)
            said = said || (w.where.file == project &&
                            w.message.find(std::string("resolution ") + value + " mm is not positive") != std::string::npos &&
                            w.message.find("using ") != std::string::npos);
        CHECK(said);
    }
}

TEST_CASE("the dexel mesher keeps the slot's volume, folds nothing, and works with one family", "[job]") {
    const fs::path dir = scratch("sharp");
    SimulateOptions o;
    o.inputs = {write(dir / "slot.ngc", kSlot)};
    o.stockBox = Box{Vec3(0.0), Vec3(40, 30, 10)};
    o.defaultTool = flatEndMill(6, {20, 40});
    o.resolution = 0.5;
    const SimulateReport r = runSimulation(o).report;
    CHECK(r.mesher == "dexel");
    CHECK(r.meshClosed);
    CHECK(r.meshFoldedTriangles == 0);
    CHECK(r.meshDegenerateTriangles == 0);
    CHECK(r.interpolatedCrossings == 0);
    CHECK(r.edgeVertices > 0);
    // The mesh keeps the slot's sharp edges: it encloses the dexel volume to within 0.02 %.
    CHECK(r.meshVolumeMm3 == Approx(r.finalVolumeMm3).epsilon(2e-4));
    o.mesher = Mesher::Vdb;
    const SimulateReport v = runSimulation(o).report;
    CHECK(v.mesher == "vdb");
    CHECK(v.meshClosed);
    // volumeToMesh rounds the edges: farther from the dexel volume.
    CHECK(std::abs(v.meshVolumeMm3 - v.finalVolumeMm3) > std::abs(r.meshVolumeMm3 - r.finalVolumeMm3));
    const auto unbounded = [](const SimulateReport& s) {
        return std::count_if(s.warnings.begin(), s.warnings.end(), [](const ReportWarning& w) {
            return w.message.find("--adaptivity with --mesher vdb is OpenVDB's own") != std::string::npos;
        });
    };
    CHECK(unbounded(v) == 0);
    // Its adaptivity has no bound on how far the surface moves, and the job says so; the dexel
    // mesher's keeps within 0.05 spacings and needs no word.
    o.adaptivity = 1.0;
    CHECK(unbounded(runSimulation(o).report) == 1);
    o.mesher = Mesher::Dexel;
    CHECK(unbounded(runSimulation(o).report) == 0);
    o.adaptivity = 0.0;
    o.mesher = Mesher::Dexel;
    o.families = FamilySet::parse("z");
    const SimulateReport z = runSimulation(o).report;
    CHECK(z.meshClosed);
    CHECK(z.interpolatedCrossings > 0);
}

TEST_CASE("a round stock: bar stock faced along its length loses its analytic cap", "[job][primitive]") {
    const fs::path dir = scratch("round");
    // A D30 flat end mill faces a bar of radius 10 along x (0 .. 40) down to z = 6 across its
    // whole width: it removes the circular segment above z = 6, r^2 acos(d / r) - d sqrt(r^2 - d^2)
    // with d = 6, times the bar's length.
    SimulateOptions o;
    o.inputs = {write(dir / "face.ngc", "G21 G90\nT1 M6\nG0 X-20 Y0 Z20\nG1 Z6 F100\nG1 X60\nG0 Z20\nM30\n")};
    o.stockFrustum = Frustum::make(Vec3(0.0), Vec3(1, 0, 0), 40, 10, 10);
    o.tools.emplace(1, flatEndMill(30, {20, 40}));
    o.resolution = 0.25;
    o.meshPath = (dir / "part.stl").string();
    const SimulateReport r = simulate(o);
    const double cap = 100 * std::acos(0.6) - 6 * 8;
    CHECK(r.stockVolumeMm3 == Approx(kPi * 100 * 40).epsilon(0.002));
    CHECK(r.removedVolumeMm3 == Approx(cap * 40).epsilon(0.005));
    CHECK(r.stockBox.lo == Vec3(0, -10, -10));
    CHECK(r.stockBox.hi == Vec3(40, 10, 10));
    CHECK(r.meshClosed);
    CHECK(r.collisions.empty());
}

TEST_CASE("simulate: a spacing coarser than half the stock's thinnest side is refused", "[job][errors][degenerate]") {
    SimulateOptions o = testing::slotJob(Vec3(2, 8, 4), Vec3(18, 8, 4), flatEndMill(3.0, {10.0, 20.0}),
                                         Box{Vec3(0.0), Vec3(20, 16, 5)});
    // Two cells across the 5 mm: 2.5 mm runs, anything coarser stops and names the largest.
    o.resolution = 2.5;
    CHECK(runSimulation(o).report.meshTriangles > 0);
    for (const double h : {2.6, 10.0, 1e6}) {
        o.resolution = h;
        CHECK_THROWS_WITH(runSimulation(o), Catch::Contains("too coarse for this 20 x 16 x 5 mm stock") &&
                                                Catch::Contains("5 mm along z") &&
                                                Catch::Contains("give --resolution 2.5 mm or less"));
    }
}

TEST_CASE("arcs whose chords stray farther than the lattice spacing are named at the arc", "[job]") {
    const fs::path dir = scratch("arc_chords");
    // A full circle of radius 5 at z -1 on its line 4.
    const std::string program = write(dir / "circle.ngc", "G21 G90\nG0 X5 Y0 Z5\nG1 Z-1\nG2 X5 Y0 I-5 J0\nG0 Z5\n");
    const auto chordWarnings = [&](double chordTolerance) {
        SimulateOptions o;
        o.inputs = {program};
        o.defaultTool = flatEndMill(2.0, {10.0, 20.0});
        o.stockBox = Box{Vec3(-8, -8, -3), Vec3(8, 8, 0)};
        o.resolution = 0.5;
        o.chordTolerance = chordTolerance;
        std::vector<ReportWarning> found;
        for (const ReportWarning& w : runSimulation(o).report.warnings)
            if (w.message.find("chords") != std::string::npos) found.push_back(w);
        return found;
    };
    // Chords within 0.2 mm of the circle: finer than the spacing, nothing to say.
    CHECK(chordWarnings(0.2).empty());
    // A tolerance past the radius: two chords across the diameter, 5 mm from the circle's far side.
    const std::vector<ReportWarning> coarse = chordWarnings(6.0);
    REQUIRE(coarse.size() == 1);
    CHECK(coarse[0].where.file == program);
    CHECK(coarse[0].where.line == 4);
    CHECK(coarse[0].message.find("up to 5 mm") != std::string::npos);
}
