// Every real program in ../shared/testdata runs end to end (with its CAMotics project where there
// is one) and gives a closed mesh; the 5-axis A/B/C programs stop with a clear error naming
// --machine, and the switchkins demo runs with its machine.
// Skips cleanly when the folder is absent.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>

#include "dexelmill/error.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/tool/builders.h"
#include "support/self_intersection.h"
#include "testdata.h"

using namespace dexelmill;
namespace fs = std::filesystem;

namespace {

/// Lattice points along the stock's longest side: coarse, so the whole set runs in seconds.
constexpr double kPointsAlongLongestSide = 120;

/// The programs to run: a folder's .camotics project stands for the programs it lists;
/// UGS's *.parsed_output.nc files are expected outputs, not programs.
std::vector<fs::path> programs(const fs::path& root) {
    std::vector<fs::path> out;
    for (const auto& e : fs::recursive_directory_iterator(root)) {
        if (!e.is_regular_file()) continue;
        const fs::path& p = e.path();
        const std::string ext = p.extension().string(), name = p.filename().string();
        if (ext == ".camotics") {
            out.push_back(p);
            continue;
        }
        if (ext != ".ngc" && ext != ".nc" && ext != ".gcode" && ext != ".apt") continue;
        if (name.find(".parsed_output.") != std::string::npos) continue;
        bool inProject = false;
        for (const auto& s : fs::directory_iterator(p.parent_path())) inProject |= s.path().extension() == ".camotics";
        // Subroutine files: they define an o-word sub for the demo programs and make no move.
        if (p.parent_path().filename() == "twp-g68.2" && (name == "square.ngc" || name == "circular_pocket.ngc"))
            continue;
        if (!inProject) out.push_back(p);
    }
    std::sort(out.begin(), out.end());
    return out;
}

/// The pairs of the mesh's triangles that meet (support/self_intersection.h), told where the first
/// lies to the next assertion when there are any.
std::size_t crossingPairs(const Mesh& mesh) {
    const testing::SelfIntersections crossing = testing::countSelfIntersections(mesh);
    if (crossing.pairs > 0)
        UNSCOPED_INFO(crossing.pairs << " pairs of triangles meet, the first at (" << crossing.at.x << ", " << crossing.at.y
                            << ", " << crossing.at.z << ")");
    return crossing.pairs;
}

}  // namespace

TEST_CASE("every shared test program runs end to end with a closed mesh without folds", "[job][testdata]") {
    if (!test::haveSharedData()) return;
    const std::vector<fs::path> all = programs(test::sharedData());
    REQUIRE(all.size() >= 25);
    for (const fs::path& p : all) {
        INFO(p.string());
        SimulateOptions o;
        o.inputs = {p.string()};
        // Programs without tools of their own get a 3 mm flat end mill with long flutes.
        o.defaultTool = flatEndMill(3, {60, 80});
        o.cellsAlongLongestSide = kPointsAlongLongestSide;
        // A program written wholly in G91 moves from wherever the tool stands: without a start
        // position none of its moves is known and nothing is left to cut, so it is given one.
        const bool incremental = p.filename() == "helical-thread-milling.gcode";
        if (incremental) {
            CHECK_THROWS_WITH(runSimulation(o), Catch::Matchers::Contains("no moves"));
            o.startPosition = Vec3(0.0);
        }
        // The switchkins demos call a subroutine file that LinuxCNC keeps in its remap folder,
        // which the testdata does not ship: a located error naming the call.
        if (p.filename().string().find("_switchkins.ngc") != std::string::npos) {
            CHECK_THROWS_WITH(runSimulation(o), Catch::Matchers::Contains("undefined subroutine"));
            continue;
        }
        const bool fiveAxis = p.string().find("xyzac") != std::string::npos || p.filename() == "rotation.ngc";
        if (fiveAxis) {
            CHECK_THROWS_WITH(runSimulation(o), Catch::Matchers::Contains("--machine"));
            // The boat and impeller take minutes (their figures are in the README); the M428 /
            // M429 demo runs here.
            if (p.filename() != "xyzac_switchkins_test_1.ngc") continue;
            o.machine = "xyzac-trt";
        }
        const Simulation s = runSimulation(o);
        CHECK(s.report.moves > 0);
        CHECK(s.report.meshTriangles > 0);
        CHECK(s.report.meshClosed);
        CHECK(s.report.meshFoldedTriangles == 0);
        CHECK(s.report.meshDegenerateTriangles == 0);
        // Before patches that share a cell kept their vertices within their crossings' box, the
        // thread-milling program left 3388 pairs here, in the bore's wall (patch_vertex.cpp).
        CHECK(crossingPairs(s.mesh) == 0);
        CHECK(s.report.finalVolumeMm3 > 0);
        CHECK(s.report.finalVolumeMm3 <= s.report.stockVolumeMm3);
    }
}

TEST_CASE("the shared CAMotics projects refined once give closed meshes without folds", "[job][testdata][refine]") {
    // Refinement splits edges and collapses the short ones it leaves; on real parts (cusps finer
    // than the lattice, walls thinner than it, crossings whose dexels graze the part) the mesh
    // must stay closed, without folded or degenerate triangles, and no triangle may pass through
    // another (before the crossing test, vcarve, slant_test, botomata_bottom and heart had 10, 8,
    // 53 and 779 such pairs).
    if (!test::haveSharedData()) return;
    std::size_t projects = 0;
    for (const fs::path& p : programs(test::sharedData())) {
        if (p.extension() != ".camotics") continue;
        ++projects;
        INFO(p.string());
        SimulateOptions o;
        o.inputs = {p.string()};  // at the project's own spacing
        o.refineRounds = 1;
        o.threads = 2;
        const Simulation s = runSimulation(o);
        CHECK(s.report.refineRounds == 1);
        CHECK(s.report.refineSplit > 0);
        CHECK(s.report.meshClosed);
        CHECK(s.report.meshFoldedTriangles == 0);
        CHECK(s.report.meshDegenerateTriangles == 0);
        CHECK(crossingPairs(s.mesh) == 0);
    }
    CHECK(projects >= 5);
}
