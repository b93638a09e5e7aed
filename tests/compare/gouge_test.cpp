// Gouges against a design, through the job: programs whose cuts into the design are known by hand
// (planar faces, flat end mills), so every depth, volume and line below is an analytic answer.
// The designs are written here as ASCII STL, polygon by polygon, sharing no code with the project.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "dexelmill/error.h"
#include "dexelmill/compare/design.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/tool/builders.h"
#include "compare/detail/deepest.h"
#include "support/scratch.h"

using namespace dexelmill;
namespace fs = std::filesystem;

namespace {

using P2 = std::array<double, 2>;

/// The solid swept by a polygon in the (x, z) plane along y from y0 to y1, as ASCII STL facets
/// facing out. The polygon is counter-clockwise seen with x to the right and z up, and every
/// vertex is visible from the first (the caps are fans from it).
std::string prismFacets(const std::vector<P2>& xz, double y0, double y1) {
    std::ostringstream s;
    s.precision(17);
    auto facet = [&](const std::array<double, 3>& a, const std::array<double, 3>& b, const std::array<double, 3>& c) {
        s << " facet normal 0 0 0\n  outer loop\n";
        for (const auto& p : {a, b, c}) s << "   vertex " << p[0] << " " << p[1] << " " << p[2] << "\n";
        s << "  endloop\n endfacet\n";
    };
    const std::size_t n = xz.size();
    auto at = [&](std::size_t i, double y) { return std::array<double, 3>{xz[i % n][0], y, xz[i % n][1]}; };
    // Counter-clockwise in (x, z) is clockwise seen from +y: the cap at y1 faces +y with the
    // order reversed, the cap at y0 faces -y as given.
    for (std::size_t i = 1; i + 1 < n; ++i) {
        facet(at(0, y0), at(i, y0), at(i + 1, y0));
        facet(at(0, y1), at(i + 1, y1), at(i, y1));
    }
    for (std::size_t i = 0; i < n; ++i) {
        facet(at(i, y0), at(i, y1), at(i + 1, y1));
        facet(at(i, y0), at(i + 1, y1), at(i + 1, y0));
    }
    return s.str();
}

/// The box [lo, hi] as ASCII STL facets facing out, each face cut into n x n rectangles of two
/// triangles: many triangles, and the distance from a point inside is still the nearest face's.
std::string tiledBoxFacets(const std::array<double, 3>& lo, const std::array<double, 3>& hi, int n) {
    std::ostringstream s;
    s.precision(17);
    for (int k = 0; k < 3; ++k)
        for (const bool high : {false, true})
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j) {
                    // Axes u = k + 1 and v = k + 2 (cyclic): counter-clockwise in (u, v) faces +k.
                    const auto u = std::size_t((k + 1) % 3), v = std::size_t((k + 2) % 3);
                    auto at = [&](int du, int dv) {
                        std::array<double, 3> p{};
                        p[std::size_t(k)] = high ? hi[std::size_t(k)] : lo[std::size_t(k)];
                        p[u] = lo[u] + (hi[u] - lo[u]) * (i + du) / n;
                        p[v] = lo[v] + (hi[v] - lo[v]) * (j + dv) / n;
                        return p;
                    };
                    std::array<std::array<double, 3>, 4> q{at(0, 0), at(1, 0), at(1, 1), at(0, 1)};
                    if (!high) std::swap(q[1], q[3]);
                    for (const auto& tri : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
                        s << " facet normal 0 0 0\n  outer loop\n";
                        for (const int c : tri)
                            s << "   vertex " << q[std::size_t(c)][0] << " " << q[std::size_t(c)][1] << " "
                              << q[std::size_t(c)][2] << "\n";
                        s << "  endloop\n endfacet\n";
                    }
                }
    return s.str();
}

/// The cube [0, side]^3 so.
std::string tiledCubeFacets(double side, int n) { return tiledBoxFacets({0.0, 0.0, 0.0}, {side, side, side}, n); }

std::string writeStl(const fs::path& p, const std::string& facets) {
    std::ofstream(p) << "solid design\n" << facets << "endsolid design\n";
    return p.string();
}

fs::path scratch(const std::string& name) { return testing::scratchFolder("dexelmill_test_design_", name); }

/// The stock of every case: 40 x 40 x 10 mm, top at z = 0, at a spacing of 0.25 mm.
const Box kStock{Vec3(0.0, 0.0, -10.0), Vec3(40.0, 40.0, 0.0)};
constexpr double kH = 0.25;

SimulateOptions job(const std::string& program, const std::string& design, double flatDiameter) {
    SimulateOptions o;
    o.inputs = {"part.ngc"};
    o.files = [program](const std::string& path) -> std::optional<std::string> {
        if (path == "part.ngc") return program;
        return std::nullopt;
    };
    o.stockBox = kStock;
    o.tools.emplace(1, flatEndMill(flatDiameter, {20.0, 40.0}));
    o.resolution = kH;
    o.designPath = design;
    o.threads = 2;
    return o;
}

/// An L-shaped design: full height for x < 30, a floor at z = -5.1 for x in [30, 40].
std::vector<P2> lShape() { return {{0, -10}, {40, -10}, {40, -5.1}, {30, -5.1}, {30, 0}, {0, 0}}; }

// Line 5: the wall pass along y at x = 35 (the cutter spans x 30..40) and z = -5: above the floor
// and tangent to the wall at x = 30, no gouge. Line 9: the floor pass at z = -5.2, 0.1 mm into the
// floor. Line 13: a rapid along the same line at z = -7. (The plunges, at y = -10, miss the stock.)
const char* kPocket =
    "G21 G90\n"
    "T1 M6\n"
    "G0 X35 Y-10 Z5\n"
    "G1 Z-5 F500\nG1 Y50\nG0 Z5\nG0 Y-10\n"
    "G1 Z-5.2\nG1 Y50\nG0 Z5\nG0 Y-10\n"
    "G0 Z-7\nG0 Y50\nG0 Z5\n"
    "M30\n";

}  // namespace

TEST_CASE("gouges: a floor cut 0.1 mm too deep, and a rapid through the design", "[compare][design][job]") {
    const fs::path dir = scratch("pocket");
    const std::string design = writeStl(dir / "l.stl", prismFacets(lShape(), -1.0, 41.0));
    const SimulateReport r = simulate(job(kPocket, design, 10.0));
    REQUIRE(r.gouges.size() == 2);
    // Deepest first: the rapid, 1.9 mm below the floor at -5.1, over the 10 x 40 mm floor from
    // -7 to -5.2 (what the floor pass left).
    const ReportGouge& rapid = r.gouges[0];
    CHECK(rapid.where.line == 13);
    CHECK(rapid.rapid);
    CHECK(rapid.depthMm == Approx(1.9).margin(1e-3));
    CHECK(rapid.volumeMm3 == Approx(10.0 * 40.0 * 1.8).epsilon(1e-5));
    const ReportGouge& floor = r.gouges[1];
    CHECK(floor.where.line == 9);
    CHECK_FALSE(floor.rapid);
    CHECK(floor.tool == 1);
    CHECK(floor.depthMm == Approx(0.1).margin(1e-3));
    CHECK(floor.volumeMm3 == Approx(10.0 * 40.0 * 0.1).epsilon(1e-4));
    CHECK(floor.point.z == Approx(-5.2).margin(1e-3));
    CHECK(floor.point.x >= 30.0);
    // The wall pass (line 5) is no gouge; the report names the design and the tolerance.
    CHECK(r.designFile == design);
    CHECK(r.gougeToleranceMm == 0.01);
    // No output shows the surface's deviation, so it was not measured.
    CHECK_FALSE(r.surfaceDeviation);
    fs::remove_all(dir);
}

TEST_CASE("gouges: named by their moves after a move swept in pieces", "[compare][design][job]") {
    // The pocket's passes after a rotary table's quarter turn there and back on xyza, 50 mm above
    // the part's axis (x), out of the stock's reach: each turn is swept in nine pieces, and the
    // gouges must still name the lines of the moves that made them.
    const fs::path dir = scratch("pieces");
    const std::string design = writeStl(dir / "l.stl", prismFacets(lShape(), -1.0, 41.0));
    std::string program = kPocket;
    program.replace(program.find("G0 X35 Y-10 Z5\n"), 15, "G0 X20 Y20 Z50 A0\nG1 A90 F100\nG1 A0\nG0 X35 Y-10 Z5\n");
    SimulateOptions o = job(program, design, 10.0);
    o.machine = "xyza";
    const SimulateReport r = simulate(o);
    REQUIRE(r.gouges.size() == 2);
    CHECK(r.gouges[0].where.line == 16);  // the rapid at z = -7, three lines later than in kPocket
    CHECK(r.gouges[0].rapid);
    CHECK(r.gouges[0].depthMm == Approx(1.9).margin(1e-3));
    CHECK(r.gouges[1].where.line == 12);  // the floor pass
    CHECK(r.gouges[1].volumeMm3 == Approx(10.0 * 40.0 * 0.1).epsilon(1e-4));
    fs::remove_all(dir);
}

TEST_CASE("gouges: a move that only touches a dexel line at its side is no gouge", "[compare][design][job]") {
    const fs::path dir = scratch("tangent");
    const std::string design = writeStl(dir / "l.stl", prismFacets(lShape(), -1.0, 41.0));
    // Line 4 plunges a D10 at (35, 20.125) to z = -5.6, 0.5 mm into the floor at -5.1: a gouge.
    // Its sides at y = 15.125 and 25.125 lie on x dexels (y = (i + 1/2) h, h = 0.25), and those at
    // z = -5.375 lie 0.275 mm inside the floor. Line 5 moves back over the plunge's own path, and
    // line 6 retracts out of the hole: each touches those dexels at a single point (x = 35) and
    // removes nothing the plunge left. Line 8 plunges at y = 20.1, off the lattice: a second gouge.
    const std::string program =
        "G21 G90\nT1 M6\nG0 X35 Y20.125 Z5\nG1 Z-5.6 F500\nG1 Z-5.3\nG0 Z5\n"
        "G0 Y10.1\nG1 Z-5.35\nG0 Z5\nM30\n";
    const SimulateReport r = simulate(job(program, design, 10.0));
    REQUIRE(r.gouges.size() == 2);
    CHECK(r.gouges[0].where.line == 4);
    CHECK(r.gouges[0].depthMm == Approx(0.5).margin(1e-3));
    CHECK(r.gouges[1].where.line == 8);
    CHECK(r.gouges[1].depthMm == Approx(0.25).margin(1e-3));
    fs::remove_all(dir);
}

TEST_CASE("gouges: a design reaching past the stock on every side", "[compare][design][job]") {
    const fs::path dir = scratch("beyond");
    // The design fills x and y -5..45 and z -15..5, around the whole stock. A pass at z = -0.005
    // takes a layer thinner than the tolerance off the top, so along each z dexel the design's
    // material (cut off by the stock's box) seemed to end 0.005 mm above the cut; in truth its top
    // is 5.005 mm above it, and the x and y dexels (the highest at z = -0.125) miss the layer.
    const std::string design = writeStl(dir / "big.stl", prismFacets({{-5, -15}, {45, -15}, {45, 5}, {-5, 5}}, -5.0, 45.0));
    const char* program = "G21 G90\nT1 M6\nG0 X5 Y-10 Z5\nG1 Z-0.005 F500\nG1 Y50\nG0 Z5\nM30\n";
    const SimulateReport r = simulate(job(program, design, 10.0));
    REQUIRE(r.gouges.size() == 1);
    CHECK(r.gouges[0].where.line == 5);
    CHECK(r.gouges[0].depthMm == Approx(5.005).margin(depthBound(0.01, kH)));
    CHECK(r.gouges[0].volumeMm3 == Approx(10.0 * 40.0 * 0.005).epsilon(1e-3));
    // The part cannot hold such a design, and the job says so, naming every side by how much.
    const auto beyond = std::find_if(r.warnings.begin(), r.warnings.end(), [](const ReportWarning& w) {
        return w.message.find("the design reaches past the stock's box") != std::string::npos;
    });
    REQUIRE(beyond != r.warnings.end());
    CHECK(beyond->where.file == design);
    for (const char* side : {"5 mm on -x", "5 mm on +x", "5 mm on -y", "5 mm on +y", "5 mm on -z", "5 mm on +z"})
        CHECK_THAT(beyond->message, Catch::Contains(side));
    fs::remove_all(dir);
}

/// The warnings of `r` that contain `text`.
std::size_t warningsWith(const SimulateReport& r, const std::string& text) {
    return std::size_t(std::count_if(r.warnings.begin(), r.warnings.end(), [&](const ReportWarning& w) {
        return w.message.find(text) != std::string::npos;
    }));
}

TEST_CASE("design: one within the stock, one past a single face, and one not closed", "[compare][design][job]") {
    const fs::path dir = scratch("inside");
    const char* program = "G21 G90\nT1 M6\nG0 X5 Y-10 Z5\nG1 Z-1 F500\nG1 Y50\nG0 Z5\nM30\n";
    // Within the stock, touching its bottom face (z = -10) and its sides at x = 0 and 40: closed,
    // and nothing to say.
    const std::string inside = writeStl(dir / "inside.stl", prismFacets({{0, -10}, {40, -10}, {40, -2}, {0, -2}}, 0.0, 40.0));
    SimulateReport r = simulate(job(program, inside, 10.0));
    CHECK(r.designClosed);
    CHECK(warningsWith(r, "reaches past the stock") == 0);
    CHECK(warningsWith(r, "not closed") == 0);
    // 0.5 mm above the stock's top, and nowhere else.
    const std::string tall = writeStl(dir / "tall.stl", prismFacets({{0, -10}, {40, -10}, {40, 0.5}, {0, 0.5}}, 0.0, 40.0));
    r = simulate(job(program, tall, 10.0));
    REQUIRE(warningsWith(r, "reaches past the stock's box (0.5 mm on +z)") == 1);
    // The same prism with one facet of its cap at y = 0 left out: the x = 5 pass's z dexels miss
    // that cap, but y dexels through the hole meet one face.
    std::string facets = prismFacets({{0, -10}, {40, -10}, {40, -2}, {0, -2}}, 0.0, 40.0);
    facets.erase(0, facets.find(" facet", 1));
    const std::string open = writeStl(dir / "open.stl", facets);
    r = simulate(job(program, open, 10.0));
    CHECK_FALSE(r.designClosed);
    CHECK(warningsWith(r, "the design is not closed") == 1);
    // A box without its bottom face: every z dexel through it meets one face, and the z family
    // casts nothing. Said as such, not as a design outside the stock.
    const std::string box = tiledBoxFacets({5, 5, -9}, {35, 35, -1}, 1);
    std::vector<std::string> facet;
    for (std::size_t at = box.find(" facet"); at != std::string::npos;) {
        const std::size_t next = box.find(" facet", at + 1);
        facet.push_back(box.substr(at, next == std::string::npos ? std::string::npos : next - at));
        at = next;
    }
    REQUIRE(facet.size() == 12);
    std::string bottomless;
    for (std::size_t i = 0; i < facet.size(); ++i)
        if (i != 8 && i != 9) bottomless += facet[i];  // the faces along z come last, the low one first
    const std::string noBottom = writeStl(dir / "no_bottom.stl", bottomless);
    CHECK_THROWS_WITH(simulate(job(program, noBottom, 10.0)),
                      Catch::Matchers::Contains("no_bottom.stl': the design is not closed") &&
                          Catch::Matchers::Contains("'dexelmill compare'"));
    fs::remove_all(dir);
}

TEST_CASE("deviation: the machined surface against the design, through the job", "[compare][deviation][job]") {
    const fs::path dir = scratch("surface");
    const std::string design = writeStl(dir / "l.stl", prismFacets(lShape(), -1.0, 41.0));
    SimulateOptions o = job(kPocket, design, 10.0);
    o.deviationPlyPath = (dir / "deviation.ply").string();
    const SimulateReport r = simulate(o);
    REQUIRE(r.surfaceDeviation);
    const Deviation& d = *r.surfaceDeviation;
    // The rapid left the floor at z = -7, 1.9 mm below the design's at -5.1. The stock's own faces
    // at y = 0 and 40 lie 1 mm inside the design's ends (y = -1 and 41); its bottom and the walls
    // the cuts did not reach lie on the design.
    CHECK(d.deepest == Approx(-1.9).margin(1e-6));
    CHECK(d.deepestPoint.z == Approx(-7.0).margin(1e-6));
    CHECK(d.farthest <= 1e-6);
    // The part is the stock less x 30..40, z -7..0: bottom 1600, top 1200, floor 400, wall at
    // x = 30 280, face x = 0 400, x = 40 120, y = 0 and 40 330 each (mm^2).
    CHECK(d.area == Approx(1600 + 1200 + 400 + 280 + 400 + 120 + 2 * 330).epsilon(1e-9));
    CHECK(fs::file_size(dir / "deviation.ply") > 1000);
    // The same without the PLY, asked for in memory.
    o.deviationPlyPath.clear();
    o.measureSurface = true;
    const Simulation s = runSimulation(o);
    REQUIRE(s.report.surfaceDeviation);
    CHECK(s.report.surfaceDeviation->deepest == d.deepest);
    REQUIRE(s.deviation.size() == s.mesh.vertices.size());
    CHECK(*std::min_element(s.deviation.begin(), s.deviation.end()) == Approx(-1.9).margin(1e-6));
    // A deviation PLY needs a design, and the .ply extension.
    o.designPath.clear();
    o.deviationPlyPath = (dir / "d.ply").string();
    CHECK_THROWS_WITH(simulate(o), Catch::Contains("give --design"));
    o.designPath = design;
    o.deviationPlyPath = (dir / "d.obj").string();
    CHECK_THROWS_WITH(simulate(o), Catch::Contains(".ply"));
    fs::remove_all(dir);
}

TEST_CASE("gouges: a slot through a boss the design keeps", "[compare][design][job]") {
    const fs::path dir = scratch("boss");
    // A base below z = -6 and a boss x 15..25, y 15..25, z -5..-1, apart from it.
    std::string facets = prismFacets({{0, -10}, {40, -10}, {40, -6}, {0, -6}}, 0.0, 40.0);
    facets += prismFacets({{15, -5}, {25, -5}, {25, -1}, {15, -1}}, 15.0, 25.0);
    const std::string design = writeStl(dir / "boss.stl", facets);
    // A D4 slot along x at y = 20, z = -2: through the boss's top millimetre, 10 x 4 x 1 mm.
    const std::string program = "G21 G90\nT1 M6\nG0 X-5 Y20 Z5\nG1 Z-2 F300\nG1 X45\nG0 Z5\nM30\n";
    const SimulateReport r = simulate(job(program, design, 4.0));
    REQUIRE(r.gouges.size() == 1);
    CHECK(r.gouges[0].where.line == 5);
    CHECK(r.gouges[0].depthMm == Approx(1.0).margin(1e-3));
    CHECK(r.gouges[0].volumeMm3 == Approx(40.0).epsilon(1e-4));
    CHECK(r.gouges[0].point.x >= 15.0);
    CHECK(r.gouges[0].point.x <= 25.0);
    fs::remove_all(dir);
}

TEST_CASE("gouges: shallower than the tolerance is not reported", "[compare][design][job]") {
    const fs::path dir = scratch("tolerance");
    // The floor at -5.195: the pass at -5.2 cuts 0.005 mm into it.
    const std::string design =
        writeStl(dir / "l.stl", prismFacets({{0, -10}, {40, -10}, {40, -5.195}, {30, -5.195}, {30, 0}, {0, 0}}, -1, 41));
    const std::string program = "G21 G90\nT1 M6\nG0 X35 Y-10 Z5\nG1 Z-5.2 F500\nG1 Y50\nG0 Z5\nM30\n";
    SimulateOptions o = job(program, design, 10.0);
    CHECK(simulate(o).gouges.empty());
    o.gougeTolerance = 0.001;
    const SimulateReport r = simulate(o);
    REQUIRE(r.gouges.size() == 1);
    CHECK(r.gouges[0].depthMm == Approx(0.005).margin(1e-3));
    fs::remove_all(dir);
}

TEST_CASE("gouges: a cut exactly as deep as the tolerance is not reported", "[compare][design][job]") {
    const fs::path dir = scratch("at_tolerance");
    // The floor at z = -5, exact in float and double. A pass at z = -5.01 cuts 0.01 mm into it, the
    // tolerance (the double -5.01 lies a hair above, so not deeper); its z dexels store the cut's
    // end as a float 4.99 mm above the stock's bottom, 2.3e-7 mm lower than the cut.
    const std::string design =
        writeStl(dir / "l.stl", prismFacets({{0, -10}, {40, -10}, {40, -5}, {30, -5}, {30, 0}, {0, 0}}, -1, 41));
    auto pass = [](const char* z) {
        return std::string("G21 G90\nT1 M6\nG0 X35 Y-10 Z5\nG1 Z") + z + " F500\nG1 Y50\nG0 Z5\nM30\n";
    };
    CHECK(simulate(job(pass("-5.01"), design, 10.0)).gouges.empty());
    // A thousandth of a millimetre deeper is a gouge, its depth that of the stored end: within a
    // float step at the stock's longest side, 40 mm, of the cut's.
    const SimulateReport r = simulate(job(pass("-5.011"), design, 10.0));
    REQUIRE(r.gouges.size() == 1);
    CHECK(r.gouges[0].where.line == 5);
    const double floatStep = std::ldexp(40.0, -23);
    CHECK(r.gouges[0].depthMm == Approx(0.011).margin(floatStep));
    fs::remove_all(dir);
}

TEST_CASE("gouges: the same for any thread count, and written as CSV", "[compare][design][job]") {
    const fs::path dir = scratch("threads");
    const std::string design = writeStl(dir / "l.stl", prismFacets(lShape(), -1.0, 41.0));
    SimulateOptions o = job(kPocket, design, 10.0);
    o.gougeCsvPath = (dir / "gouges.csv").string();
    std::vector<SimulateReport> runs;
    for (int threads : {1, 3}) {
        o.threads = threads;
        runs.push_back(simulate(o));
    }
    REQUIRE(runs[0].gouges.size() == runs[1].gouges.size());
    for (std::size_t i = 0; i < runs[0].gouges.size(); ++i) {
        CHECK(runs[0].gouges[i].move == runs[1].gouges[i].move);
        CHECK(runs[0].gouges[i].depthMm == runs[1].gouges[i].depthMm);
        CHECK(runs[0].gouges[i].volumeMm3 == runs[1].gouges[i].volumeMm3);
    }
    std::ifstream in(dir / "gouges.csv");
    std::string header, first;
    std::getline(in, header);
    std::getline(in, first);
    CHECK(header == "move,file,line,tool,depth_mm,volume_mm3,x,y,z,rapid");
    // The rapid on line 13 is kPocket's tenth move: line 3 only sets the start position, and
    // lines 4 to 13 move once each.
    CHECK(first.rfind("10,\"part.ngc\",13,1,1.9", 0) == 0);
    CHECK(runs[1].gouges[0].move == 10);
    CHECK(first.substr(first.size() - 2) == ",1");
    fs::remove_all(dir);
}

TEST_CASE("gouges: a design that cannot be read, and a CSV without a design", "[compare][design][job]") {
    const fs::path dir = scratch("errors");
    SimulateOptions o = job(kPocket, (dir / "part.obj").string(), 10.0);
    CHECK_THROWS_WITH(simulate(o), Catch::Contains("part.obj") && Catch::Contains("STL"));
    o.designPath = (dir / "missing.stl").string();
    CHECK_THROWS_WITH(simulate(o), Catch::Contains("missing.stl"));
    // A program that fails is reported before a design that cannot be read, on either thread
    // count.
    for (const int threads : {1, 2}) {
        SimulateOptions bad = job("G21\nG1 X1 Y\n", (dir / "missing.stl").string(), 10.0);
        bad.threads = threads;
        CHECK_THROWS_WITH(simulate(bad), Catch::Contains("part.ngc:2") && !Catch::Contains("missing.stl"));
    }
    o.designPath.clear();
    o.gougeCsvPath = (dir / "g.csv").string();
    CHECK_THROWS_WITH(simulate(o), Catch::Contains("--design"));
    CHECK_FALSE(fs::exists(dir / "g.csv"));
    fs::remove_all(dir);
}

TEST_CASE("gouges: the deepest point between samples is found within the stated bound", "[compare][design]") {
    const fs::path dir = scratch("peak");
    // A 10 mm cube. Along the line y = z = 5 the depth is min(x, 10 - x): a peak of 5 at x = 5,
    // which the samples half a spacing apart (h = 2) from x = 0.3 miss by 0.19 mm.
    const std::string design = writeStl(dir / "cube.stl", prismFacets({{0, 0}, {10, 0}, {10, 10}, {0, 10}}, 0.0, 10.0));
    const Lattice lattice = Lattice::fromBox(Box{Vec3(0.0), Vec3(10.0)}, 2.0);
    const DesignPart part = loadDesign(design, lattice);
    CutResult cut;
    cut.moves.resize(3);
    cut.moves[0].designRemoved = {1.0, 2.0, 3.0};
    // Move 0: the stretch through the peak, and a shallower one (y = 3: at most 3 deep).
    cut.designStretches.push_back({0, Axis::X, 2, 2, 0.3f, 9.1f});
    cut.designStretches.push_back({0, Axis::X, 1, 2, 0.3f, 9.1f});
    // Move 2: a stretch along z at x = y = 9, 1 mm from two faces: at most 1 deep.
    cut.designStretches.push_back({2, Axis::Z, 4, 4, 2.0f, 8.0f});
    const double tolerance = 0.01;
    std::vector<Gouge> gouges = findGouges(part, lattice, cut, tolerance);
    REQUIRE(gouges.size() == 2);
    CHECK(gouges[0].move == 0);
    CHECK(gouges[0].depth <= 5.0 + 1e-12);
    CHECK(gouges[0].depth >= 5.0 - depthBound(tolerance, lattice.h));
    CHECK(gouges[0].point.y == 5.0);
    CHECK(gouges[0].point.x == Approx(5.0).margin(depthBound(tolerance, lattice.h)));
    CHECK(gouges[0].volume == 3.0);  // the z family's measure
    CHECK(gouges[1].move == 2);
    CHECK(gouges[1].depth == Approx(1.0).margin(1e-12));
    // A tolerance above both depths reports nothing.
    CHECK(findGouges(part, lattice, cut, 5.5).empty());
    fs::remove_all(dir);
}

TEST_CASE("design: the distance index built when first asked for, by threads at once", "[compare][design]") {
    const fs::path dir = scratch("lazy");
    // A 10 mm cube: from a point inside it the distance is the nearest face's, min over the axes
    // of min(c, 10 - c).
    const std::string path = writeStl(dir / "cube.stl", prismFacets({{0, 0}, {10, 0}, {10, 10}, {0, 10}}, 0.0, 10.0));
    const Lattice lattice = Lattice::fromBox(Box{Vec3(0.0), Vec3(10.0)}, 1.0);
    for (const bool signs : {false, true}) {
        DesignPart part = loadDesign(readDesign(path), path, lattice, FamilySet::all(), signs);
        std::vector<double> found(4000, -1.0);
        tbb::task_arena arena(3);
        arena.execute([&] {
            tbb::parallel_for(std::size_t(0), found.size(), [&](std::size_t i) {
                const Vec3 p(0.5 + 9.0 * double(i % 17) / 16.0, 0.5 + 9.0 * double(i % 13) / 12.0,
                             0.5 + 9.0 * double(i % 11) / 10.0);
                found[i] = part.distance().distance(p);
            });
        });
        for (std::size_t i = 0; i < found.size(); ++i) {
            const Vec3 p(0.5 + 9.0 * double(i % 17) / 16.0, 0.5 + 9.0 * double(i % 13) / 12.0,
                         0.5 + 9.0 * double(i % 11) / 10.0);
            double expected = 10.0;
            for (int k = 0; k < 3; ++k) expected = std::min({expected, p[k], 10.0 - p[k]});
            CHECK(found[i] == Approx(expected).margin(1e-12));
        }
        // Handed over, the index leaves the part.
        const std::unique_ptr<MeshDistance> taken = part.takeDistance();
        REQUIRE(taken);
        CHECK(taken->distance(Vec3(5.0, 5.0, 9.0)) == Approx(1.0));
        CHECK_THROWS_AS(part.distance(), Error);
    }
    fs::remove_all(dir);
}

TEST_CASE("design: distances near a few regions from an index of the triangles there", "[compare][design]") {
    const fs::path dir = scratch("near");
    // A 10 mm cube of 2,400 triangles: inside, the distance is the nearest face's.
    const std::string path = writeStl(dir / "cube.stl", tiledCubeFacets(10.0, 20));
    const Lattice lattice = Lattice::fromBox(Box{Vec3(0.0), Vec3(10.0)}, 0.5);
    const DesignPart part = loadDesign(readDesign(path), path, lattice, FamilySet::all(), false);
    auto cube = [](const Vec3& p) {
        double d = 10.0;
        for (int k = 0; k < 3; ++k) d = std::min({d, p[k], 10.0 - p[k]});
        return d;
    };
    // Around (5, 5, 0.5), 1 mm each way: the nearest points of the points within 0.5 mm of its
    // centre lie on the floor inside it.
    const NearDistance near = part.distanceNear({Box{Vec3(4.0, 4.0, -0.5), Vec3(6.0, 6.0, 1.5)}});
    REQUIRE(near.local);
    CHECK(near.index == near.local.get());
    CHECK(near.local->triangleCount() > 0);
    CHECK(near.local->triangleCount() <= 72);  // the floor's 6 x 6 squares that meet the box
    for (const Vec3& p : {Vec3(5.0, 5.0, 0.5), Vec3(5.2, 4.9, 0.3), Vec3(4.6, 5.4, 0.9), Vec3(5.0, 5.0, 0.0)})
        CHECK((*near).distance(p) == Approx(cube(p)).margin(1e-12));
    // No region: nothing to answer, and nothing to build.
    const NearDistance none = part.distanceNear({});
    REQUIRE(none.local);
    CHECK(none.local->triangleCount() == 0);
    // A region reaching more than a quarter of the triangles takes the whole index.
    const NearDistance wide = part.distanceNear({Box{Vec3(-1.0), Vec3(6.0, 11.0, 11.0)}});
    CHECK_FALSE(wide.local);
    CHECK(wide.index == &part.distance());
    // So does a region without bound, on a part whose index is not built yet.
    const DesignPart other = loadDesign(readDesign(path), path, lattice, FamilySet::all(), false);
    const double inf = std::numeric_limits<double>::infinity();
    const NearDistance unbounded = other.distanceNear({Box{Vec3(5.0, 5.0, -inf), Vec3(5.0, 5.0, inf)}});
    CHECK_FALSE(unbounded.local);
    CHECK(unbounded.index == &other.distance());
    // Once the whole index is built, it answers.
    const NearDistance later = part.distanceNear({Box{Vec3(4.0, 4.0, -0.5), Vec3(6.0, 6.0, 1.5)}});
    CHECK_FALSE(later.local);
    CHECK(later.index == &part.distance());
    fs::remove_all(dir);
}

TEST_CASE("gouges: a stretch deeper than the local index reaches is measured on the whole design", "[compare][design]") {
    const fs::path dir = scratch("reach");
    const std::string path = writeStl(dir / "cube.stl", tiledCubeFacets(10.0, 20));
    // h = 0.5: the local index looks 2 mm around each stretch (kNearSpacings h).
    const Lattice lattice = Lattice::fromBox(Box{Vec3(0.0), Vec3(10.0)}, 0.5);
    REQUIRE(kNearSpacings * lattice.h == 2.0);
    const DesignPart part = loadDesign(readDesign(path), path, lattice, FamilySet::all(), false);
    CutResult cut;
    cut.moves.resize(2);
    // Both along x from 4 to 6 mm, inside the design's segment [0, 10] of that dexel: it reaches
    // 5 mm. Move 0 at y = 3.25, z = 4.75: 3.25 mm deep, beyond the local index's 2 mm. No face
    // lies within 2 mm of it; the nearest the local index holds is the top, 5.25 mm away (taken
    // for move 1). Move 1 at y = 5.25, z = 9.25: 0.75 mm below the top, which the local index
    // answers.
    cut.designStretches.push_back({0, Axis::X, 6, 9, 4.0f, 6.0f, 5.0});
    cut.designStretches.push_back({1, Axis::X, 10, 18, 4.0f, 6.0f, 5.0});
    const std::vector<Gouge> gouges = findGouges(part, lattice, cut, 0.01);
    REQUIRE(gouges.size() == 2);
    CHECK(gouges[0].move == 0);
    CHECK(gouges[0].depth == Approx(3.25).margin(1e-12));
    CHECK(gouges[0].point.y == 3.25);
    CHECK(gouges[1].move == 1);
    CHECK(gouges[1].depth == Approx(0.75).margin(1e-12));
    CHECK(gouges[1].point.z == 9.25);
    fs::remove_all(dir);
}

TEST_CASE("gouges: the stock a design implies, with and without a stated size", "[compare][design]") {
    const Box design{Vec3(2.0, 2.0, -30.0), Vec3(117.0, 117.0, -19.0)};
    std::string note;
    const Box plain = designStockBox(design, std::nullopt, note);
    CHECK(plain.lo == design.lo);
    CHECK(plain.hi == design.hi);
    CHECK(note.find("bounding box") != std::string::npos);
    // A stated 119 x 119 x 30 mm: centred in x and y, top at the work zero.
    StatedStock stated{Vec3(119.0, 119.0, 30.0), {"p.apt", 4, 1}};
    const Box placed = designStockBox(design, stated, note);
    CHECK(placed.lo == Vec3(0.0, 0.0, -30.0));
    CHECK(placed.hi == Vec3(119.0, 119.0, 0.0));
    CHECK(note.find("p.apt:4") != std::string::npos);
    CHECK(note.find("top at z = 0") != std::string::npos);
    // A design above the work zero keeps its bottom.
    const Box raised{Vec3(0.0, 0.0, 1.0), Vec3(10.0, 10.0, 5.0)};
    const Box up = designStockBox(raised, StatedStock{Vec3(10.0, 12.0, 6.0), {"p.apt", 4, 1}}, note);
    CHECK(up.lo == Vec3(0.0, -1.0, 1.0));
    CHECK(up.hi == Vec3(10.0, 11.0, 7.0));
    // A stated size smaller than the design is an error at its line.
    CHECK_THROWS_WITH(designStockBox(design, StatedStock{Vec3(119.0, 100.0, 30.0), {"p.apt", 4, 1}}, note),
                      Catch::Contains("p.apt:4") && Catch::Contains("along y"));
}

TEST_CASE("gouges: with no stock given, the stock is the design's box", "[compare][design][job]") {
    const fs::path dir = scratch("stockless");
    const std::string design = writeStl(dir / "l.stl", prismFacets(lShape(), 0.0, 40.0));
    SimulateOptions o = job(kPocket, design, 10.0);
    o.stockBox.reset();
    const SimulateReport r = simulate(o);
    CHECK(r.stockBox.lo == Vec3(0.0, 0.0, -10.0));
    CHECK(r.stockBox.hi == Vec3(40.0, 40.0, 0.0));
    bool said = false;
    for (const ReportWarning& w : r.warnings) said |= w.message.find("design's bounding box") != std::string::npos;
    CHECK(said);
    CHECK(r.gouges.size() == 2);
    fs::remove_all(dir);
}

TEST_CASE("gouges: a design in another frame, placed by a transform", "[compare][design][job]") {
    const fs::path dir = scratch("transform");
    // The L-shaped design of the pocket case, mirrored in x (x -> 40 - x) and then shifted by
    // (0, 0, 100): the map back, p -> diag(-1, 1, 1) p + (40, 0, -100), mirrors, so its faces are
    // reversed to face out again.
    // Mirroring reverses the polygon's turn: walk it backwards from the same first vertex.
    const std::vector<P2> l = lShape();
    std::vector<P2> mirrored;
    for (std::size_t i = 0; i < l.size(); ++i) {
        const P2& p = l[(l.size() - i) % l.size()];
        mirrored.push_back({40.0 - p[0], p[1] + 100.0});
    }
    const std::string design = writeStl(dir / "m.stl", prismFacets(mirrored, -1.0, 41.0));
    SimulateOptions o = job(kPocket, design, 10.0);
    CHECK_THROWS_WITH(simulate(o), Catch::Contains("no material inside"));  // unplaced, it misses the stock
    Affine back;
    back.m = {{{-1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}};
    back.t = Vec3(40.0, 0.0, -100.0);
    o.designTransform = back;
    const SimulateReport r = simulate(o);
    REQUIRE(r.gouges.size() == 2);
    CHECK(r.gouges[0].where.line == 13);
    CHECK(r.gouges[0].depthMm == Approx(1.9).margin(1e-3));
    CHECK(r.gouges[1].where.line == 9);
    CHECK(r.gouges[1].depthMm == Approx(0.1).margin(1e-3));
    CHECK(r.gouges[1].volumeMm3 == Approx(40.0).epsilon(1e-4));
    // A map that flattens the design is refused.
    back.m[2] = {0.0, 0.0, 0.0};
    o.designTransform = back;
    CHECK_THROWS_WITH(simulate(o), Catch::Contains("m.stl") && Catch::Contains("determinant"));
    fs::remove_all(dir);
}

TEST_CASE("excess: 0.5 mm left on a wall", "[compare][design][job]") {
    const fs::path dir = scratch("excess");
    const std::string design = writeStl(dir / "l.stl", prismFacets(lShape(), -1.0, 41.0));
    // A D10 pass at x = 35.5 and z = -5.1 along y: the floor exactly, and 0.5 mm short of the wall at
    // x = 30, which keeps a 0.5 x 5.1 x 40 mm layer outside the design.
    const std::string program = "G21 G90\nT1 M6\nG0 X35.5 Y-10 Z5\nG1 Z-5.1 F500\nG1 Y50\nG0 Z5\nM30\n";
    const SimulateReport r = simulate(job(program, design, 10.0));
    CHECK(r.gouges.empty());
    CHECK(r.excessToleranceMm == 0.05);
    CHECK(r.excessThicknessMm == Approx(0.5).margin(0.01 * kH));
    CHECK(r.excessPoint.x == Approx(30.5).margin(1e-6));
    CHECK(r.excessVolumeMm3 == Approx(0.5 * 5.1 * 40.0).epsilon(1e-4));
    REQUIRE(r.excessRegions.size() == 1);
    CHECK(r.excessRegions[0].volumeMm3 == Approx(0.5 * 5.1 * 40.0).epsilon(1e-4));
    CHECK(r.excessRegions[0].box.lo.x <= 30.0);
    CHECK(r.excessRegions[0].box.hi.x >= 30.5);
    // A tolerance above the layer's thickness leaves no region, and the volume stays.
    SimulateOptions o = job(program, design, 10.0);
    o.excessTolerance = 0.6;
    const SimulateReport loose = simulate(o);
    CHECK(loose.excessRegions.empty());
    CHECK(loose.excessThicknessMm == 0.0);
    CHECK(loose.excessVolumeMm3 == Approx(r.excessVolumeMm3));
    fs::remove_all(dir);
}

TEST_CASE("excess: 2.5 mm left on a wall, thicker than the local search reaches", "[compare][design][job]") {
    const fs::path dir = scratch("excess_thick");
    const std::string design = writeStl(dir / "l.stl", prismFacets(lShape(), -1.0, 41.0));
    // A D10 pass at x = 37.5 cuts x in [32.5, 42.5] down to the floor, keeping a 2.5 x 5.1 x 40 mm
    // layer on the wall at x = 30. Its farthest points, on its face at x = 32.5 and at least 2.5 mm
    // above the floor, lie 2.5 mm from the design: beyond the 4 h = 1 mm the first, local search
    // looks, so it is measured again against the whole design.
    REQUIRE(2.5 > kNearSpacings * kH);
    const std::string program = "G21 G90\nT1 M6\nG0 X37.5 Y-10 Z5\nG1 Z-5.1 F500\nG1 Y50\nG0 Z5\nM30\n";
    const SimulateReport r = simulate(job(program, design, 10.0));
    CHECK(r.gouges.empty());
    CHECK(r.excessThicknessMm == Approx(2.5).margin(0.01 * kH));
    CHECK(r.excessPoint.x == Approx(32.5).margin(1e-6));
    CHECK(r.excessVolumeMm3 == Approx(2.5 * 5.1 * 40.0).epsilon(1e-4));
    REQUIRE(r.excessRegions.size() == 1);
    CHECK(r.excessRegions[0].thicknessMm == Approx(2.5).margin(0.01 * kH));
    fs::remove_all(dir);
}

TEST_CASE("excess: an island of stock far from the design is measured on the whole design", "[compare][design][job]") {
    const fs::path dir = scratch("excess_island");
    // The design: the block x in [0, 10] across the stock, 9,600 triangles. A D20 pass at x = 20
    // clears x in [10, 30], which leaves the island x in [30, 40]: its far face lies 30 mm from the
    // design. No design triangle lies within 4 h of the island, so the first, local search finds
    // nothing there and the island is measured again against the whole design.
    const std::string design = writeStl(dir / "block.stl", tiledBoxFacets({0.0, -1.0, -11.0}, {10.0, 41.0, 1.0}, 40));
    const std::string program = "G21 G90\nT1 M6\nG0 X20 Y-15 Z5\nG1 Z-10.5 F500\nG1 Y55\nG0 Z5\nM30\n";
    const SimulateReport r = simulate(job(program, design, 20.0));
    CHECK(r.gouges.empty());
    CHECK(r.excessThicknessMm == Approx(30.0).margin(0.01 * kH));
    CHECK(r.excessPoint.x == Approx(40.0).margin(1e-6));
    CHECK(r.excessVolumeMm3 == Approx(10.0 * 40.0 * 10.0).epsilon(1e-4));
    fs::remove_all(dir);
}

TEST_CASE("excess: two walls left apart are two regions, the same for any thread count", "[compare][design][job]") {
    const fs::path dir = scratch("excess_regions");
    // Two blocks, x in [0, 18] and [22, 40], full height: the design is the stock with a 4 mm slot.
    const std::string design =
        writeStl(dir / "two.stl", prismFacets({{0, -10}, {18, -10}, {18, 0}, {0, 0}}, -1.0, 41.0) +
                                      prismFacets({{22, -10}, {40, -10}, {40, 0}, {22, 0}}, -1.0, 41.0));
    // A D3 pass through the stock at x = 20.25 cuts x in [18.75, 21.75]: 0.75 mm stays on the left
    // wall and 0.25 mm on the right, 3 mm apart, both on lattice planes (h = 0.25).
    const std::string program = "G21 G90\nT1 M6\nG0 X20.25 Y-10 Z5\nG1 Z-10.5 F500\nG1 Y50\nG0 Z5\nM30\n";
    std::vector<SimulateReport> runs;
    for (int threads : {1, 3}) {
        SimulateOptions o = job(program, design, 3.0);
        o.threads = threads;
        runs.push_back(simulate(o));
    }
    const SimulateReport& r = runs[0];
    CHECK(r.gouges.empty());
    CHECK(r.excessVolumeMm3 == Approx((0.75 + 0.25) * 10.0 * 40.0).epsilon(1e-4));
    CHECK(r.excessThicknessMm == Approx(0.75).margin(0.01 * kH));
    CHECK(r.excessPoint.x == Approx(18.75).margin(1e-6));
    REQUIRE(r.excessRegions.size() == 2);
    // Most volume first.
    CHECK(r.excessRegions[0].volumeMm3 == Approx(0.75 * 10.0 * 40.0).epsilon(1e-4));
    CHECK(r.excessRegions[0].thicknessMm == Approx(0.75).margin(0.01 * kH));
    CHECK(r.excessRegions[0].box.hi.x <= 20.0);
    CHECK(r.excessRegions[1].volumeMm3 == Approx(0.25 * 10.0 * 40.0).epsilon(1e-4));
    CHECK(r.excessRegions[1].thicknessMm == Approx(0.25).margin(0.01 * kH));
    CHECK(r.excessRegions[1].box.lo.x >= 20.0);
    // Bit for bit, whatever the threads.
    const SimulateReport& s = runs[1];
    CHECK(s.excessVolumeMm3 == r.excessVolumeMm3);
    CHECK(s.excessThicknessMm == r.excessThicknessMm);
    CHECK(s.excessPoint == r.excessPoint);
    REQUIRE(s.excessRegions.size() == r.excessRegions.size());
    for (std::size_t i = 0; i < r.excessRegions.size(); ++i) {
        CHECK(s.excessRegions[i].volumeMm3 == r.excessRegions[i].volumeMm3);
        CHECK(s.excessRegions[i].thicknessMm == r.excessRegions[i].thicknessMm);
        CHECK(s.excessRegions[i].point == r.excessRegions[i].point);
    }
    fs::remove_all(dir);
}
