// Refinement against the exact part, through the job: ball passes whose cusps are finer than the
// lattice, measured against the analytic part they leave (support/face_deviation.h, no code shared
// with the sweep or the refinement).
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "dexelmill/io/mesh_io.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/refine/refine.h"
#include "dexelmill/tool/builders.h"
#include "support/face_deviation.h"
#include "support/scratch.h"
#include "support/self_intersection.h"

using namespace dexelmill;
using dexelmill::testing::CarvedPart;
using dexelmill::testing::FaceDeviation;
namespace fs = std::filesystem;

namespace {

// A ball of radius 1.5875 mm (1/8") at a stepover of 0.375 mm, as on CAMotics' bear: cusps
// s^2 / (8 r) = 0.011 mm high, 0.037 of the 0.3 mm spacing, with a period of 1.25 spacings.
const double kDiameter = 3.175, kRadius = kDiameter / 2.0, kStep = 0.375, kTipZ = 8.0, kH = 0.3;
const Box kStock{Vec3(10.0, 10.0, 0.0), Vec3(22.0, 22.0, 10.0)};
const double kFirstY = 13.0, kLastY = 19.0;

/// Passes along x that start and end beyond the stock, so that inside it each pass is a cylinder
/// below the ball's centre and a slab above it.
std::string passesProgram() {
    std::ostringstream g;
    g << "G21 G90 G17\nT1 M6\nG0 X5 Y" << kFirstY << " Z12\n";
    for (double y = kFirstY; y <= kLastY + 1e-9; y += kStep)
        g << "G0 X5 Y" << y << " Z12\nG1 Z" << kTipZ << " F500\nG1 X27\nG0 Z12\n";
    g << "M30\n";
    return g.str();
}

CarvedPart passesPart() {
    CarvedPart part{kStock, {}};
    const double zc = kTipZ + kRadius;
    for (double y = kFirstY; y <= kLastY + 1e-9; y += kStep) {
        part.cuts.push_back(testing::cylinder(Vec3(0.0, y, zc), Vec3(1.0, 0.0, 0.0), kRadius));
        part.cuts.push_back(testing::boxCutter({Vec3(-100.0, y - kRadius, zc), Vec3(100.0, y + kRadius, 100.0)}));
    }
    return part;
}

SimulateOptions job(const std::string& program, int rounds, int threads = 2) {
    SimulateOptions o;
    o.inputs = {"passes.ngc"};
    o.files = [program](const std::string& path) -> std::optional<std::string> {
        if (path == "passes.ngc") return program;
        return std::nullopt;
    };
    o.stockBox = kStock;
    o.tools.emplace(1, ballEndMill(kDiameter, {20.0, 40.0}));
    o.resolution = kH;
    o.refineRounds = rounds;
    o.threads = threads;
    return o;
}

std::string summary(const char* name, const Simulation& s, const FaceDeviation& d) {
    std::ostringstream out;
    out << name << ": faces RMS " << d.rms / kH << " h, p99 " << d.p99 / kH << " h, max " << d.max / kH
        << " h at (" << d.worst.x << ", " << d.worst.y << ", " << d.worst.z << "); " << s.mesh.triangles.size()
        << " triangles, " << s.report.refineSplit << " edges split, " << s.report.refineRefused << " refused";
    return out.str();
}

/// Whether exact membership changes within `delta` of p: the cube of half-side delta about p,
/// sampled at its corners, edge midpoints, face centres and centre, holds points inside the part
/// and points outside (so a point on the block's edge counts too).
bool onSurface(const CarvedPart& part, const Vec3& p, double delta) {
    bool in = false, out = false;
    for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
            for (int k = -1; k <= 1; ++k) (part.inside(p + delta * Vec3(i, j, k)) ? in : out) = true;
    return in && out;
}

}  // namespace

TEST_CASE("refine: ball passes come out with the cusps the lattice cannot see", "[refine]") {
    const CarvedPart part = passesPart();
    const std::string program = passesProgram();
    const Simulation plain = runSimulation(job(program, 0));
    const Simulation refined = runSimulation(job(program, 2));
    const FaceDeviation before = measureFaces(plain.mesh, part, 3.0 * kH);
    const FaceDeviation after = measureFaces(refined.mesh, part, 3.0 * kH);
    INFO(summary("mesher", plain, before));
    INFO(summary("refined", refined, after));

    const MeshCheck check = checkMesh(refined.mesh);
    CHECK(check.ok());
    CHECK(testing::countSelfIntersections(plain.mesh).pairs == 0);
    CHECK(testing::countSelfIntersections(refined.mesh).pairs == 0);
    CHECK(refined.report.meshClosed);
    CHECK(refined.report.meshFoldedTriangles == 0);
    CHECK(refined.report.refineRounds == 2);
    CHECK(refined.report.refineSplit > 0);
    CHECK(after.misses == 0);
    // Measured: RMS 0.0041 h -> 0.00057 h, p99 0.020 h -> 0.0016 h, max 0.031 h -> 0.015 h.
    CHECK(after.rms <= 0.5 * before.rms);
    CHECK(after.p99 <= 0.6 * before.p99);
    CHECK(after.max <= before.max);
    CHECK(after.rms <= 0.003 * kH);
    // The volume: the block's length along x times the integral over y of the material's height,
    // under the lowest groove bottom (midpoint rule on 1e-4 mm steps; the height is continuous).
    double area = 0.0;
    const double dy = 1e-4;
    for (double y = kStock.lo.y + 0.5 * dy; y < kStock.hi.y; y += dy) {
        double top = kStock.hi.z;
        for (double yi = kFirstY; yi <= kLastY + 1e-9; yi += kStep)
            if (std::abs(y - yi) < kRadius)
                top = std::min(top, kTipZ + kRadius - std::sqrt(kRadius * kRadius - (y - yi) * (y - yi)));
        area += (top - kStock.lo.z) * dy;
    }
    const double exact = area * (kStock.hi.x - kStock.lo.x);
    const double errorBefore = std::abs(plain.report.meshVolumeMm3 - exact) / exact;
    const double errorAfter = std::abs(refined.report.meshVolumeMm3 - exact) / exact;
    INFO("volume error " << errorBefore * 100 << " % -> " << errorAfter * 100 << " %");
    // Measured: 0.0011 % before, 0.0023 % after (the mesher's is already within its crossings' reach).
    CHECK(errorAfter <= 1e-4);  // the 0.01 %

    // Every vertex refinement moved or made lies on the exact part's surface (to the sweep's 1e-6 mm,
    // with a margin for the oracle's own bisection). The mesher's vertices left where they were
    // are known by their places (the short edges' collapse may renumber them), and lie on the part
    // too, to the refinement's tolerance (0.002 h): one whose nearest axis finds no crossing, or
    // whose move there folds the mesh, is moved along another axis.
    REQUIRE(refined.mesh.vertices.size() > plain.mesh.vertices.size());
    std::set<std::array<double, 3>> mesher, kept;
    for (const Vec3& p : plain.mesh.vertices) mesher.insert({p.x, p.y, p.z});
    std::size_t off = 0, left = 0;
    for (const Vec3& p : refined.mesh.vertices) {
        if (mesher.count({p.x, p.y, p.z})) {
            kept.insert({p.x, p.y, p.z});
            left += !onSurface(part, p, 0.002 * kH);
        } else {
            off += !onSurface(part, p, 1e-5);
        }
    }
    // The mesher's vertices no longer in their places were moved, or collapsed into a neighbour.
    const std::size_t gone = mesher.size() - kept.size();
    INFO(gone << " of the mesher's vertices moved or collapsed (" << refined.report.refineSnapped << " moved, "
              << refined.report.refineCollapsed << " edges collapsed), " << left << " left off the part");
    CHECK(off == 0);
    CHECK(left == 0);
    CHECK(gone >= refined.report.refineSnapped);
    CHECK(gone <= refined.report.refineSnapped + refined.report.refineCollapsed);
}

TEST_CASE("refine: the result does not depend on the thread count", "[refine]") {
    const std::string program = passesProgram();
    const Simulation one = runSimulation(job(program, 1, 1));
    const Simulation three = runSimulation(job(program, 1, 3));
    REQUIRE(one.mesh.vertices.size() == three.mesh.vertices.size());
    REQUIRE(one.mesh.triangles.size() == three.mesh.triangles.size());
    CHECK(std::equal(one.mesh.vertices.begin(), one.mesh.vertices.end(), three.mesh.vertices.begin()));
    CHECK(std::equal(one.mesh.triangles.begin(), one.mesh.triangles.end(), three.mesh.triangles.begin()));
}

TEST_CASE("refine: an uncut block and zero rounds are left as they are", "[refine]") {
    // Only rapids far above the block: the mesh is the block's faces, whose midpoints are exact
    // (and no sweep comes near them, so none is even cut).
    const std::string above = "G21 G90\nT1 M6\nG0 X5 Y5 Z30\nG0 X30 Y30 Z30\nM30\n";
    const Simulation plain = runSimulation(job(above, 0));
    const Simulation refined = runSimulation(job(above, 3));
    CHECK(refined.report.refineSplit == 0);
    CHECK(refined.report.meshClosed);
    REQUIRE(refined.mesh.triangles.size() == plain.mesh.triangles.size());
    CHECK(std::equal(refined.mesh.vertices.begin(), refined.mesh.vertices.end(), plain.mesh.vertices.begin()));
    // The same block with its top face crossed by one pass: only the pass's region is tested.
    const std::string one = "G21 G90\nT1 M6\nG0 X5 Y16 Z12\nG1 Z8 F500\nG1 X27\nG0 Z12\nM30\n";
    const Simulation pass = runSimulation(job(one, 1));
    CHECK(pass.report.refineQueries > 0);
    // Every vertex and edge tested would be about twice the triangles.
    CHECK(pass.report.refineQueries < pass.report.meshTriangles / 2);
    CHECK(pass.report.meshClosed);

    const Simulation none = runSimulation(job(passesProgram(), 0));
    CHECK(none.report.refineRounds == 0);
    CHECK(none.report.refineQueries == 0);
}

TEST_CASE("refine: a stock from a file is not refined, and the report says why", "[refine]") {
    const fs::path dir = testing::scratchFolder("dexelmill_test_refine_", "stock");
    // The block itself, as an STL: the stock the box would be, but from a file.
    const std::string above = "G21 G90\nT1 M6\nG0 X5 Y5 Z30\nM30\n";
    const Simulation block = runSimulation(job(above, 0));
    const std::string stl = (dir / "block.stl").string();
    writeStl(stl, block.mesh);

    SimulateOptions o = job(passesProgram(), 2);
    o.stockBox.reset();
    o.stockFile = stl;
    const Simulation s = runSimulation(o);
    CHECK(s.report.refineRounds == 0);
    CHECK(s.report.refineQueries == 0);
    bool warned = false;
    for (const ReportWarning& w : s.report.warnings) warned |= w.message.find("--refine needs a box stock") != std::string::npos;
    CHECK(warned);
    fs::remove_all(dir);
}

TEST_CASE("refine: a round that would not fit in memory is not started", "[refine]") {
    const Simulation plain = runSimulation(job(passesProgram(), 0));
    Mesh mesh = plain.mesh;
    RefineOptions o;
    o.rounds = 2;
    o.tolerance = 0.002 * kH;
    o.window = 0.5 * kH;
    // Room for the first round only: the second starts from a mesh with more triangles.
    o.memoryBytes = kRoundBytesPerTriangle * double(mesh.triangles.size()) * 1.01;
    RefineStats stats;
    refineMesh(mesh, kStock, plain.program.path, plain.tools, o, &stats);
    CHECK(stats.rounds == 1);
    CHECK(stats.split > 0);
    CHECK(stats.roundNeeded > o.memoryBytes);
    CHECK(stats.check.ok());

    // No room at all: the mesh is left as it is, and checked.
    Mesh untouched = plain.mesh;
    o.memoryBytes = 1.0;
    RefineStats none;
    refineMesh(untouched, kStock, plain.program.path, plain.tools, o, &none);
    CHECK(none.rounds == 0);
    CHECK(none.roundNeeded > 0.0);
    CHECK(untouched.triangles.size() == plain.mesh.triangles.size());
    CHECK(none.check.ok());
}

namespace {

/// A flat mill D6 (tool 1) faces the block [0, 10]^3 down to z = 5; `after` is G-code run next,
/// with a ball end D4 as tool 2.
Simulation facedBlock(const std::string& after = "") {
    const std::string facing = "G21 G90\nT1 M6\nG0 X-5 Y0 Z12\nG1 Z5 F500\nG1 X15\nG1 Y3\nG1 X-5\nG1 Y6\nG1 X15\n"
                               "G1 Y9\nG1 X-5\nG1 Y12\nG1 X15\nG0 Z12\n";
    SimulateOptions o = job(facing + after + "M30\n", 0);
    o.stockBox = Box{Vec3(0.0), Vec3(10.0)};
    o.tools.clear();
    o.tools.emplace(1, flatEndMill(6.0, {20.0, 40.0}));
    o.tools.emplace(2, ballEndMill(4.0, {20.0, 40.0}));
    return runSimulation(o);
}

/// A closed tetrahedron, its triangles facing outwards; vertex 0 is the apex.
Mesh tetrahedron(const std::array<Vec3, 4>& corners) {
    Mesh tetra;
    tetra.vertices.assign(corners.begin(), corners.end());
    const Vec3 centre = 0.25 * (corners[0] + corners[1] + corners[2] + corners[3]);
    for (Mesh::Triangle t : {Mesh::Triangle{0, 1, 2}, Mesh::Triangle{0, 1, 3}, Mesh::Triangle{0, 2, 3},
                             Mesh::Triangle{1, 2, 3}}) {
        const Vec3 a = tetra.vertices[t[0]], b = tetra.vertices[t[1]], c = tetra.vertices[t[2]];
        if (glm::dot(glm::cross(b - a, c - a), a - centre) < 0.0) std::swap(t[1], t[2]);
        tetra.triangles.push_back(t);
    }
    return tetra;
}

/// One round of refinement of `mesh` against the job `s` on the block [0, size]^3 (the faced
/// block's by default), with windows of 0.5 mm.
RefineStats refineAgainst(const Simulation& s, Mesh& mesh, double size = 10.0) {
    RefineOptions ro;
    ro.rounds = 1;
    ro.window = 0.5;
    RefineStats stats;
    refineMesh(mesh, Box{Vec3(0.0), Vec3(size)}, s.program.path, s.tools, ro, &stats);
    return stats;
}

/// A ball-end mill of diameter d plunged to z = 8 at the middle of the block [0, size]^3.
Simulation plungedBall(double d, double size) {
    const double mid = size / 2.0;
    std::ostringstream g;
    g << "G21 G90\nT1 M6\nG0 X" << mid << " Y" << mid << " Z" << size + 5.0 << "\nG1 Z8 F500\nG0 Z" << size + 5.0
      << "\nM30\n";
    SimulateOptions o = job(g.str(), 0);
    o.stockBox = Box{Vec3(0.0), Vec3(size)};
    o.tools.clear();
    o.tools.emplace(1, ballEndMill(d, {20.0, 40.0}));
    return runSimulation(o);
}

}  // namespace

TEST_CASE("refine: a vertex whose nearest axis finds no crossing is moved along another", "[refine]") {
    // A flat mill faces the block down to z = 5. The mesh is one tetrahedron: its apex 0.1 mm
    // above the floor, its base deep in the material and tilted so that the apex's normal is
    // (-0.90, 0, 0.44). Along x the apex's window runs through air (no crossing); along z it
    // meets the floor 0.1 mm below. The base lies 0.6 mm or more inside: its windows (0.5 mm)
    // find no surface.
    const Simulation s = facedBlock();
    Mesh tetra = tetrahedron({Vec3(5.0, 5.0, 5.1), Vec3(6.0, 3.0, 4.4), Vec3(6.0, 7.0, 4.4), Vec3(5.02, 5.0, 2.4)});
    REQUIRE(checkMesh(tetra).ok());

    const RefineStats stats = refineAgainst(s, tetra);
    const Vec3 apex = tetra.vertices[0];
    INFO("queries " << stats.queries << " snapped " << stats.snapped << " refused " << stats.snapRefused << " split " << stats.split);
    INFO("apex at (" << apex.x << ", " << apex.y << ", " << apex.z << ")");
    CHECK(stats.snapped == 1);
    CHECK(apex.x == 5.0);
    CHECK(apex.y == 5.0);
    CHECK(apex.z == Approx(5.0).margin(1e-6));
    CHECK(stats.check.ok());
}

TEST_CASE("refine: a vertex inside the material is not moved out along another axis", "[refine]") {
    // The block of the case above, faced down to z = 5, and the same tetrahedron with its apex
    // 0.1 mm below the floor instead of above it: inside the material, as a vertex the mesher put
    // in a wall thinner than the lattice showed. Along x its window finds no crossing; along z
    // the floor lies 0.1 mm above, outwards, and the vertex stays. The base lies 0.7 mm or more
    // inside.
    const Simulation s = facedBlock();
    Mesh tetra = tetrahedron({Vec3(5.0, 5.0, 4.9), Vec3(6.0, 3.0, 4.2), Vec3(6.0, 7.0, 4.2), Vec3(5.02, 5.0, 2.2)});
    REQUIRE(checkMesh(tetra).ok());
    // The apex's normal (the sum of its triangles' area vectors) is nearest x and within 75
    // degrees of z, so its z window is asked.
    Vec3 apexNormal(0.0);
    for (std::size_t t = 0; t < tetra.triangles.size(); ++t)
        if (tetra.triangles[t][0] == 0 || tetra.triangles[t][1] == 0 || tetra.triangles[t][2] == 0)
            apexNormal += tetra.areaVector(t);
    apexNormal = glm::normalize(apexNormal);
    INFO("apex normal (" << apexNormal.x << ", " << apexNormal.y << ", " << apexNormal.z << ")");
    REQUIRE(std::abs(apexNormal.x) > std::abs(apexNormal.z));
    REQUIRE(apexNormal.z > 0.2588);

    const RefineStats stats = refineAgainst(s, tetra);
    INFO("queries " << stats.queries << " snapped " << stats.snapped << " split " << stats.split);
    CHECK(stats.snapped == 0);
    CHECK(tetra.vertices[0] == Vec3(5.0, 5.0, 4.9));
    CHECK(stats.check.ok());
}

TEST_CASE("refine: a vertex no window reaches is asked again a spacing away along its nearest axis", "[refine]") {
    // The faced block again (floor at z = 5), and a tetrahedron standing on a base at z = 2.8,
    // deep in the material, with its apex inside it too, below the floor: the end of a wedge that
    // the mesher stopped short of its tip. The apex's normal is +z (its triangles' area vectors
    // sum to minus the base's), so x and y are not asked; along z the floor lies `depth` above,
    // outwards. Windows reach 0.5 mm, and the second try twice as far.
    const Simulation s = facedBlock();
    const double depth = GENERATE(0.3, 0.7, 0.95, 1.2);
    Mesh tetra = tetrahedron({Vec3(5.0, 5.0, 5.0 - depth), Vec3(4.0, 4.0, 2.8), Vec3(6.0, 4.0, 2.8), Vec3(5.0, 6.0, 2.8)});
    REQUIRE(checkMesh(tetra).ok());

    const RefineStats stats = refineAgainst(s, tetra);
    const Vec3 apex = tetra.vertices[0];
    INFO("depth " << depth << ": apex at (" << apex.x << ", " << apex.y << ", " << apex.z << "), snapped "
                  << stats.snapped << ", split " << stats.split);
    CHECK(apex.x == 5.0);
    CHECK(apex.y == 5.0);
    if (depth < 1.0) {
        CHECK(stats.snapped == 1);
        CHECK(apex.z == Approx(5.0).margin(1e-6));
    } else {
        CHECK(stats.snapped == 0);
        CHECK(apex.z == 5.0 - depth);
    }
    for (std::uint32_t v = 1; v < 4; ++v) CHECK(tetra.vertices[v].z == 2.8);
    CHECK(stats.check.ok());
}

TEST_CASE("refine: a vertex whose move onto the part folds is moved part of the way", "[refine]") {
    // The faced block (floor at z = 5) with a groove along y: a ball D4 at x = 5, its tip at
    // z = 3, so the groove's side is the circle (x - 5)^2 + (z - 5)^2 = 4, steep near its top
    // edge x = 7. A mesh round that edge: a vertex 0.01 mm over the groove and 0.1 mm above the
    // floor, two neighbours on the floor and two on the groove's side 0.1 mm below its edge (on
    // the part, so they stay), closed below deep in the material. Along z the vertex's window
    // falls to the groove's side at z = 4.80, below the side's neighbours, and the move folds the
    // mesh; half way, at z = 4.95, it does not. (Bear's wall tops, whose corner a cusp lowered.)
    const Simulation s = facedBlock("T2 M6\nG0 X5 Y-5 Z12\nG1 Z3\nG1 Y15\nG0 Z12\n");

    const double side = 5.0 + std::sqrt(4.0 - 0.01);  // the groove's side at z = 4.9
    Mesh mesh;
    mesh.vertices = {Vec3(6.99, 5.0, 5.1), Vec3(7.5, 4.5, 5.0),  Vec3(7.5, 5.5, 5.0),
                     Vec3(side, 5.5, 4.9), Vec3(side, 4.5, 4.9), Vec3(8.5, 5.0, 3.0)};
    // The ring round vertex 0, anticlockwise seen from above, and vertex 5 below it.
    const std::array<std::uint32_t, 4> ring{1, 2, 3, 4};
    for (std::size_t k = 0; k < 4; ++k) {
        mesh.triangles.push_back({0, ring[k], ring[(k + 1) % 4]});
        mesh.triangles.push_back({5, ring[(k + 1) % 4], ring[k]});
    }
    REQUIRE(checkMesh(mesh).ok());
    REQUIRE(meshVolume(mesh) > 0.0);

    const RefineStats stats = refineAgainst(s, mesh);
    const Vec3 v = mesh.vertices[0];
    INFO("vertex at (" << v.x << ", " << v.y << ", " << v.z << "), snapped " << stats.snapped << " ("
                       << stats.snapPartial << " part of the way), refused " << stats.snapRefused);
    CHECK(stats.snapPartial == 1);
    CHECK(v.x == 6.99);
    CHECK(v.y == 5.0);
    CHECK(v.z == Approx(5.1 - 0.5 * (5.1 - (5.0 - std::sqrt(4.0 - 1.99 * 1.99)))).margin(1e-6));
    CHECK(stats.check.ok());
    CHECK(testing::countSelfIntersections(mesh).pairs == 0);
}

TEST_CASE("refine: a midpoint whose window slides along the part is split along a nearer axis", "[refine]") {
    // A ball D3.175 plunged to z = 8 at (5, 5) leaves a spherical dimple in the block [0, 10]^3,
    // centred at (5, 5, 8 + r). The edge from (4.6, 5, zs) to (5.4, 5, zs) has both ends on it,
    // and its midpoint lies r - sqrt(r^2 - 0.4^2) = 0.0512 mm above the dimple's bottom. Its two
    // triangles face nearly +y (a wall) and up-and-+y, as at the crease of a wall's top, so the
    // window runs along y: it meets the sphere 0.4 mm away, at (5, 4.6, zs), half the edge's
    // length along the part, and a split there would cut across the dimple. Along z the bottom
    // lies 0.0512 mm below. The other corners lie 1.45 mm inside the material and 0.6 mm above
    // the block, beyond the windows' 0.5 mm.
    const double r = 3.175 / 2.0;
    const double zs = 8.0 + r - std::sqrt(r * r - 0.16);
    const Simulation s = plungedBall(3.175, 10.0);
    Mesh tetra = tetrahedron({Vec3(4.6, 5.0, zs), Vec3(5.4, 5.0, zs), Vec3(5.0, 5.3, 6.55), Vec3(5.0, 3.0, 10.6)});
    REQUIRE(checkMesh(tetra).ok());
    // The premise: the edge's normal is nearest y, and z lies within 75 degrees of it.
    Vec3 edgeNormal(0.0);
    for (std::size_t t = 0; t < tetra.triangles.size(); ++t) {
        const Mesh::Triangle& tri = tetra.triangles[t];
        if (std::count(tri.begin(), tri.end(), 0u) && std::count(tri.begin(), tri.end(), 1u))
            edgeNormal += glm::normalize(tetra.areaVector(t));
    }
    edgeNormal = glm::normalize(edgeNormal);
    INFO("edge normal (" << edgeNormal.x << ", " << edgeNormal.y << ", " << edgeNormal.z << ")");
    REQUIRE(edgeNormal.y > edgeNormal.z);
    REQUIRE(edgeNormal.z > 0.2588);

    const RefineStats stats = refineAgainst(s, tetra);
    INFO("queries " << stats.queries << " snapped " << stats.snapped << " split " << stats.split << " refused "
                    << stats.refused << " along another axis " << stats.laterAxis);
    const auto near = [&](const Vec3& p) {
        return std::any_of(tetra.vertices.begin(), tetra.vertices.end(),
                           [&](const Vec3& v) { return glm::length(v - p) < 1e-5; });
    };
    CHECK(near(Vec3(4.6, 5.0, zs)));
    CHECK(near(Vec3(5.4, 5.0, zs)));
    CHECK(near(Vec3(5.0, 5.0, 8.0)));
    CHECK_FALSE(near(Vec3(5.0, 4.6, zs)));
    CHECK(stats.laterAxis >= 1);
    CHECK(stats.check.ok());
}

TEST_CASE("refine: a triangle cut under a ridge gives up a flank's split, not the ridge's", "[refine]") {
    // Two grooves along x, a ball D4 at y = 4 and y = 6 whose centre runs down the line
    // z = 5 + s (x - 5), s = 0.3, leave a ridge at y = 5 where both cylinders of radius 2 about
    // those lines meet: a point (x, 5, z) lies 1 off each line across and (z - 5 - s (x - 5)) /
    // sqrt(1 + s^2) along, so the ridge is z = 5 + s (x - 5) - sqrt(3 (1 + s^2)), and a flank
    // point at distance d from its groove's line across is z = 5 + s (x - 5) - sqrt((4 - d^2)
    // (1 + s^2)). The triangle A B C has A on the ridge at x = 5.25 and B, C on the flanks at
    // (5, 5 +- 0.6): its edge B C passes 0.238 mm under the ridge, its edges A B and A C 0.029 mm
    // above the flanks. Split at all three crossings along z, its middle piece faces away from it
    // (cos -0.05, worked out from the six points); without the split of B C the pieces are good,
    // and they are good without A B's (or A C's) too. Refusing a flank's split, 0.029 mm off,
    // puts a vertex on the ridge over B C; refusing the ridge's left B C 0.238 mm under it. The
    // other triangle of B C, with its corner E on the ridge at x = 4.5, takes every split.
    const double s = 0.3, k = std::sqrt(1.0 + s * s);
    const auto ridge = [&](double x) { return 5.0 + s * (x - 5.0) - std::sqrt(3.0) * k; };
    const double flank = 5.0 - std::sqrt(4.0 - 0.4 * 0.4) * k;  // at x = 5, 0.4 from either line
    std::ostringstream g;
    g << "G21 G90\nT1 M6\n";
    for (const double y : {4.0, 6.0})
        g << "G0 X-3 Y" << y << " Z12\nG1 Z" << 3.0 + s * (-3.0 - 5.0) << " F500\nG1 X13 Z" << 3.0 + s * (13.0 - 5.0)
          << "\nG0 Z12\n";
    g << "M30\n";
    SimulateOptions o = job(g.str(), 0);
    o.stockBox = Box{Vec3(0.0), Vec3(10.0)};
    o.tools.clear();
    o.tools.emplace(1, ballEndMill(4.0, {20.0, 40.0}));
    const Simulation sim = runSimulation(o);

    // A, B, C, E inside a ring of six points on the part round them, whose outline runs down to
    // D, so that the four have only the part's side of the mesh round them.
    const auto onPart = [&](double x, double y) {
        const double d = std::min(std::abs(y - 4.0), std::abs(y - 6.0));  // across, to the nearer line
        return Vec3(x, y, 5.0 + s * (x - 5.0) - std::sqrt(4.0 - d * d) * k);
    };
    Mesh mesh;
    mesh.vertices = {Vec3(5.25, 5.0, ridge(5.25)), Vec3(5.0, 5.6, flank), Vec3(5.0, 4.4, flank),
                     Vec3(4.5, 5.0, ridge(4.5)),   onPart(6.2, 5.0),       onPart(5.6, 6.3),
                     onPart(4.4, 6.3),             onPart(3.6, 5.0),       onPart(4.4, 3.7),
                     onPart(5.6, 3.7),             Vec3(4.9, 5.0, 1.5)};
    // Anticlockwise seen from above: the two triangles of B C, the ring, and the outline to D.
    mesh.triangles = {{0, 1, 2}, {3, 2, 1}, {0, 4, 5}, {0, 5, 1}, {1, 5, 6}, {1, 6, 3},  {3, 6, 7},
                      {3, 7, 8}, {3, 8, 2}, {2, 8, 9}, {2, 9, 0}, {0, 9, 4}};
    for (std::uint32_t r = 0; r < 6; ++r) mesh.triangles.push_back({4 + (r + 1) % 6, 4 + r, 10});
    REQUIRE(checkMesh(mesh).ok());
    REQUIRE(meshVolume(mesh) > 0.0);

    const RefineStats stats = refineAgainst(sim, mesh);
    INFO("snapped " << stats.snapped << " split " << stats.split << " refused " << stats.refused);
    const Vec3 onRidge(5.0, 5.0, ridge(5.0));
    const bool split = std::any_of(mesh.vertices.begin(), mesh.vertices.end(),
                                   [&](const Vec3& v) { return glm::length(v - onRidge) < 1e-5; });
    CHECK(split);
    CHECK(stats.check.ok());
    CHECK(testing::countSelfIntersections(mesh).pairs == 0);
}

TEST_CASE("refine: a vertex whose window slides along the part is moved along a nearer axis", "[refine]") {
    // A ball D10 plunged to z = 8 at (10, 10) leaves a spherical dimple, centred at (10, 10, 13),
    // in the block [0, 20]^3. The apex of the tetrahedron lies 0.05 mm off its side where the side
    // is 80 degrees from the bottom, nearly vertical, in the dimple's air; the apex's normal is
    // (0.55, 0, 0.835), nearest z, as at the crease of a wall's top. Along z its window slides down
    // the side and meets it 0.252 mm below, a fifth of the apex's longest edge (1.3 mm); along x
    // the side is 0.051 mm away. The base lies 0.59 mm or more inside the material.
    const Vec3 centre(10.0, 10.0, 13.0);
    const double r = 5.0, phi = 80.0 * M_PI / 180.0;
    const Vec3 side = centre + r * Vec3(-std::sin(phi), 0.0, -std::cos(phi));
    const Vec3 apex = side + 0.05 * glm::normalize(centre - side);
    const Vec3 n = glm::normalize(Vec3(0.55, 0.0, 0.835));
    const Vec3 u = glm::normalize(glm::cross(n, Vec3(0.0, 1.0, 0.0))), w = glm::cross(n, u);
    std::array<Vec3, 4> corners{apex};
    for (int k = 0; k < 3; ++k) {
        const double a = (90.0 + 120.0 * k) * M_PI / 180.0;
        corners[std::size_t(k + 1)] = apex - 1.2 * n + 0.5 * (std::cos(a) * u + std::sin(a) * w);
    }
    Mesh tetra = tetrahedron(corners);
    REQUIRE(checkMesh(tetra).ok());
    const Simulation s = plungedBall(10.0, 20.0);

    const RefineStats stats = refineAgainst(s, tetra, 20.0);
    INFO("queries " << stats.queries << " snapped " << stats.snapped << " split " << stats.split
                    << " along another axis " << stats.laterAxis);
    const Vec3 moved = tetra.vertices[0];
    INFO("apex at (" << moved.x << ", " << moved.y << ", " << moved.z << ")");
    // On the side along x: the sphere's point at the apex's y and z, on the near side.
    const double dz = apex.z - centre.z;
    CHECK(moved.x == Approx(centre.x - std::sqrt(r * r - dz * dz)).margin(1e-5));
    CHECK(moved.y == apex.y);
    CHECK(moved.z == apex.z);
    CHECK(stats.laterAxis >= 1);
    CHECK(stats.check.ok());
}

namespace {

/// A ball-end mill (radius r, reaching `length` above its tip) on APT MULTAX moves: the tip runs
/// straight, the axis turns on the great circle. Membership of the swept part is tested against
/// `kPoses` poses per move, taken here from the motion law's own formula; between two poses a
/// tool point moves at most 0.02 mm, so the sampled union lies within 0.02^2 / (8 r) = 2e-5 mm of
/// the swept one (the ball and the side are smooth; the top rim never reaches the stock).
struct TurningBall {
    static constexpr int kPoses = 2000;
    double r = 3.0, length = 30.0;
    std::vector<Vec3> tips, axes;
    /// Per move: its tips' segment, and where its poses start.
    std::vector<std::array<Vec3, 2>> segments;
    std::vector<std::size_t> first;
    std::vector<double> step;  ///< per move: the farthest any tool point goes from one pose to the next

    void move(const Vec3& p0, const Vec3& a0, const Vec3& p1, const Vec3& a1) {
        segments.push_back({p0, p1});
        first.push_back(tips.size());
        const double theta = std::acos(std::clamp(glm::dot(a0, a1), -1.0, 1.0));
        step.push_back((glm::length(p1 - p0) + theta * std::hypot(length, r)) / kPoses);
        for (int k = 0; k <= kPoses; ++k) {
            const double u = double(k) / kPoses;
            tips.push_back(p0 + u * (p1 - p0));
            axes.push_back(theta < 1e-12 ? a1
                                         : (std::sin((1.0 - u) * theta) * a0 + std::sin(u * theta) * a1) /
                                               std::sin(theta));
        }
    }
    bool inside(const Vec3& p) const {
        for (std::size_t m = 0; m < segments.size(); ++m)
            if (insideMove(p, m)) return true;
        return false;
    }
    bool insideMove(const Vec3& p, std::size_t m) const {
        // Every point of the tool lies within hypot(length, r) of its tip.
        const Vec3 a = segments[m][0], f = segments[m][1] - a;
        const double u = glm::dot(f, f) > 0.0 ? std::clamp(glm::dot(p - a, f) / glm::dot(f, f), 0.0, 1.0) : 0.0;
        if (glm::length(p - (a + u * f)) > std::hypot(length, r)) return false;
        const std::size_t end = m + 1 < first.size() ? first[m + 1] : tips.size();
        for (std::size_t k = first[m]; k < end; ++k) {
            const Vec3 d = p - tips[k];
            const double s = glm::dot(d, axes[k]);
            // The tool lies within r of its axis segment, and comes no nearer by more than one
            // step a pose: poses that cannot reach p yet are skipped.
            const double gap = glm::length(d - std::clamp(s, 0.0, length) * axes[k]) - r;
            if (gap > 2.0 * step[m]) {
                k += std::size_t(gap / step[m]) - 1;
                continue;
            }
            if (s < r) {
                const Vec3 c = d - r * axes[k];
                if (glm::dot(c, c) < r * r) return true;
            } else if (s <= length && glm::dot(d, d) - s * s < r * r) {
                return true;
            }
        }
        return false;
    }
};

}  // namespace

TEST_CASE("refine: moves whose tool axis turns are followed within their tolerance", "[refine][turning]") {
    const fs::path dir = testing::scratchFolder("dexelmill_test_refine_", "turning");
    // Two passes 4 mm apart, each turning the axis from 20 degrees one way to 20 the other, 3 mm
    // deep in the block: the ridge between them is a cusp 0.76 mm high, which the 0.5 mm lattice
    // sees only where its lines cross it.
    const double s20 = std::sin(20.0 * M_PI / 180.0), c20 = std::cos(20.0 * M_PI / 180.0);
    const Vec3 left(-s20, 0.0, c20), right(s20, 0.0, c20);
    std::ostringstream apt;
    apt.precision(9);
    apt << "MULTAX\nCUTTER/6,3\nFROM/0,5,2," << left.x << ",0," << left.z << "\nGOTO/20,5,2," << right.x << ",0,"
        << right.z << "\nGOTO/20,9,2," << right.x << ",0," << right.z << "\nGOTO/0,9,2," << left.x << ",0," << left.z
        << "\nFINI\n";
    const std::string path = (dir / "turning.apt").string();
    {
        std::ofstream(path) << apt.str();
    }
    TurningBall ball;
    ball.move(Vec3(0, 5, 2), left, Vec3(20, 5, 2), right);
    ball.move(Vec3(20, 5, 2), right, Vec3(20, 9, 2), right);
    ball.move(Vec3(20, 9, 2), right, Vec3(0, 9, 2), left);
    const Box stock{Vec3(-6.0, 0.0, -2.0), Vec3(26.0, 14.0, 5.0)};
    // Each stage's last report, in the order the stages came.
    std::vector<std::pair<std::string, std::pair<std::size_t, std::size_t>>> stages;
    auto run = [&](int rounds) {
        SimulateOptions o;
        o.inputs = {path};
        o.stockBox = stock;
        o.resolution = 0.5;
        o.refineRounds = rounds;
        o.threads = 2;
        o.progress = [&](const char* stage, std::size_t done, std::size_t total) {
            if (stages.empty() || stages.back().first != stage) stages.push_back({stage, {}});
            stages.back().second = {done, total};
        };
        return runSimulation(o);
    };
    const Simulation plain = run(0);
    stages.clear();
    const Simulation refined = run(1);
    // The refinement's progress: the vertices' windows, then the round's, each to its end.
    std::map<std::string, std::pair<std::size_t, std::size_t>> last(stages.begin(), stages.end());
    for (const char* stage : {"snap 1", "refine 1"}) {
        INFO(stage);
        REQUIRE(last.count(stage) == 1);
        CHECK(last[stage].second > 0);
        CHECK(last[stage].first == last[stage].second);
    }
    CHECK(refined.report.refineRounds == 1);
    CHECK(refined.report.refineSplit > 0);
    CHECK(refined.report.refineSnapped > 0);
    CHECK(checkMesh(refined.mesh).ok());
    CHECK(testing::countSelfIntersections(refined.mesh).pairs == 0);
    for (const ReportWarning& w : refined.report.warnings) CHECK(w.message.find("--refine") == std::string::npos);

    // Every vertex refinement moved or made lies within the turn tolerance (1e-4 mm) of the swept
    // part's surface, plus the oracle's sampling (2e-5 mm): onSurface's cube of half-side delta
    // sees a plane within delta / sqrt(3) of its centre. Those whose every move onto the part
    // folded the mesh, moved part of the way, are the exception the report counts.
    const double delta = std::sqrt(3.0) * (kDefaultTurnTolerance + 3e-5);
    CarvedPart part{stock, {}};
    testing::Cutter sweep;
    sweep.inside = [&](const Vec3& p) { return ball.inside(p); };
    part.cuts.push_back(sweep);
    REQUIRE(refined.mesh.vertices.size() > plain.mesh.vertices.size());
    // The mesher's vertices left where they were are known by their places (the short edges'
    // collapse renumbers them).
    std::set<std::array<double, 3>> unmoved;
    for (const Vec3& p : plain.mesh.vertices) unmoved.insert({p.x, p.y, p.z});
    std::size_t off = 0, checked = 0, turningRegion = 0;
    for (const Vec3& p : refined.mesh.vertices) {
        if (unmoved.count({p.x, p.y, p.z})) continue;
        ++checked;
        turningRegion += p.x > 1.0 && p.x < 19.0 && p.z > 2.0 && p.z < 4.9;
        if (!onSurface(part, p, delta)) {
            ++off;
            UNSCOPED_INFO("off the part: (" << p.x << ", " << p.y << ", " << p.z << ")");
        }
    }
    INFO(checked << " vertices moved or made, " << turningRegion << " of them under the turning moves, "
                 << refined.report.refineSnapPartial << " moved part of the way");
    CHECK(turningRegion > 100);
    CHECK(off <= refined.report.refineSnapPartial);
    CHECK(refined.report.refineSnapPartial * 100 < checked);
    // The unrefined mesher's vertices are not all that close: the test can tell.
    bool plainOff = false;
    for (std::size_t v = 0; v < plain.mesh.vertices.size() && !plainOff; ++v)
        plainOff = !onSurface(part, plain.mesh.vertices[v], delta);
    CHECK(plainOff);
    fs::remove_all(dir);
}
