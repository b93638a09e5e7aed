// The dexel mesher against analytic parts: box stocks carved dexel by dexel with exact ends and
// normals (support/analytic_parts.h), measured by an oracle that shares no code with the mesher:
// points spread evenly over the triangles, each moved along its face normal to the nearest change
// of exact membership (stock box minus the cutters) and bisected there.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <random>

#include "dexelmill/stock/fine_features.h"
#include "dexelmill/surface/contour.h"
#include "dexelmill/surface/levelset.h"
#include "support/analytic_parts.h"
#include "support/face_deviation.h"
#include "support/self_intersection.h"

using namespace dexelmill;
using dexelmill::testing::Cutter;
using dexelmill::testing::FaceDeviation;
using dexelmill::testing::measureFaces;
using Part = dexelmill::testing::CarvedPart;

namespace {

/// A box stock carved by the cutters, rebuilt and contoured.
struct Result {
    Mesh mesh;
    MeshCheck check;
    ContourStats stats;
    FaceDeviation faces;
    double h;
};

Result contourPart(const Part& part, double h, FamilySet families = FamilySet::all(),
                   std::optional<std::array<int, 3>> indexOffset = std::nullopt) {
    TriDexelStock stock = TriDexelStock::fromBox(part.box, h, families);
    for (const Cutter& c : part.cuts) testing::carve(stock, c);
    RebuildOptions rebuild;
    rebuild.families = families;
    rebuild.indexOffset = indexOffset;
    const LevelSet ls = rebuildLevelSet(stock, rebuild);
    Result r;
    r.h = h;
    r.mesh = contourStock(ls, stock, {}, &r.stats);
    r.check = checkMesh(r.mesh);
    r.faces = measureFaces(r.mesh, part, 3.0 * h);
    // Every case's mesh is embedded: no two triangles meet but in what they share.
    const testing::SelfIntersections crossing = testing::countSelfIntersections(r.mesh);
    INFO("h " << h << ": " << crossing.pairs << " pairs of triangles meet, the first " << crossing.first[0] << " and "
              << crossing.first[1] << " at (" << crossing.at.x << ", " << crossing.at.y << ", " << crossing.at.z
              << "); " << crossing.tested << " pairs tested");
    CHECK(crossing.pairs == 0);
    return r;
}

/// What a case measured, shown with its checks.
std::string summary(const char* name, const Result& r) {
    std::ostringstream out;
    out << name << " at h " << r.h << ": faces RMS " << r.faces.rms / r.h << " h, p99 " << r.faces.p99 / r.h
        << " h, max " << r.faces.max / r.h << " h at (" << r.faces.worst.x << ", " << r.faces.worst.y << ", "
        << r.faces.worst.z << "); " << r.mesh.triangles.size() << " triangles, " << r.check.foldedTriangles
        << " folded, " << r.stats.edgeVertices << " edge and " << r.stats.cornerVertices << " corner vertices, "
        << r.stats.flipped << " chords flipped, " << r.stats.pulledBack << " vertices pulled back";
    return out.str();
}

const Box kBox{Vec3(0.0), Vec3(32.0, 32.0, 24.0)};

/// Contoured at h = 1: the part that two plunges of a flat end mill of radius 15 leave in the box
/// (5, 5, 0)-(15, 15, 3), their walls `gap` apart at `neck`, their centres on a line `turn` rad
/// from x.
Result finOfTwoPlunges(double gap, double turn, const Vec3& neck) {
    const double h = 1.0, r = 15.0;
    const Vec3 apart(std::cos(turn), std::sin(turn), 0.0), up(0.0, 0.0, 1.0);
    const Part part{Box{Vec3(5.0, 5.0, 0.0), Vec3(15.0, 15.0, 3.0)},
                    {testing::cylinder(neck - (r + 0.5 * gap) * apart, up, r),
                     testing::cylinder(neck + (r + 0.5 * gap) * apart, up, r)}};
    return contourPart(part, h);
}

/// Contoured at h = 1: the part that two ball plunges of radius r (15 unless given) leave in the box
/// (5, 5, 0)-(15, 15, 3), their surfaces `gap` apart at `neck`, their centres on a line `turn` rad
/// from x about z and `elevation` rad above the xy plane.
Result finOfTwoBalls(double gap, double turn, double elevation, const Vec3& neck, double r = 15.0) {
    const double h = 1.0;
    const Vec3 apart(std::cos(turn) * std::cos(elevation), std::sin(turn) * std::cos(elevation), std::sin(elevation));
    const Part part{Box{Vec3(5.0, 5.0, 0.0), Vec3(15.0, 15.0, 3.0)},
                    {testing::sphere(neck - (r + 0.5 * gap) * apart, r), testing::sphere(neck + (r + 0.5 * gap) * apart, r)}};
    return contourPart(part, h);
}

/// Contoured at h = 1: all that is left of the box (5, 5, 0)-(15, 15, 3) is a plate `thickness`
/// thick whose middle passes through `centre`, its normal `turn` rad from x about z and
/// `elevation` rad above the xy plane.
Result plate(double thickness, double turn, double elevation, const Vec3& centre) {
    const Vec3 n(std::cos(turn) * std::cos(elevation), std::sin(turn) * std::cos(elevation),
                 std::sin(elevation));
    const double d = glm::dot(n, centre);
    const Part part{Box{Vec3(5.0, 5.0, 0.0), Vec3(15.0, 15.0, 3.0)},
                    {testing::halfSpaces({{n, d - 0.5 * thickness}}),
                     testing::halfSpaces({{-n, -(d + 0.5 * thickness)}})}};
    return contourPart(part, 1.0);
}

/// A fin meshed from its dexels with its patches apart: no fold, no crossing pair (contourPart
/// checks them), no split edge dropped.
void checkFinApart(const char* name, const Result& res) {
    INFO(summary(name, res) << "; " << res.stats.splitEdges << " split edges");
    CHECK(res.check.ok());
    CHECK(res.stats.splitEdges > 0);  // the fin is meshed from its dexels
    CHECK(res.stats.splitEdgesDropped == 0);
}

}  // namespace

TEST_CASE("contour: a spherical dimple", "[surface][contour]") {
    const Part part{kBox, {testing::sphere(Vec3(16.3, 15.8, 30.1), 12.0)}};
    const Result r = contourPart(part, 1.0);
    INFO(summary("sphere", r));
    CHECK(r.check.ok());
    CHECK(r.faces.misses == 0);
    // Measured: RMS 0.0021 h, max 0.082 h at the rim where the dimple meets the top face.
    CHECK(r.faces.rms <= 0.004 * r.h);
    CHECK(r.faces.max <= 0.12 * r.h);
}

TEST_CASE("contour: an inclined cylinder and a torus", "[surface][contour]") {
    const Part cyl{kBox, {testing::cylinder(Vec3(16.0, 16.0, 24.0), Vec3(1.0, 0.4, 0.3), 6.0)}};
    const Result rc = contourPart(cyl, 1.0);
    INFO(summary("cylinder", rc));
    CHECK(rc.check.ok());
    // Measured: RMS 0.0046 h, max 0.22 h where the cylinder leaves the block through its side
    // and top (a convex corner, kept within its crossings' box).
    CHECK(rc.faces.rms <= 0.008 * rc.h);
    CHECK(rc.faces.max <= 0.3 * rc.h);
    const Part tor{kBox, {testing::torus(Vec3(16.2, 15.9, 24.0), Vec3(0.2, -0.1, 1.0), 9.0, 4.0)}};
    const Result rt = contourPart(tor, 1.0);
    INFO(summary("torus", rt));
    CHECK(rt.check.ok());
    // Measured: RMS 0.0052 h, max 0.12 h at the rim on the top face.
    CHECK(rt.faces.rms <= 0.008 * rt.h);
    CHECK(rt.faces.max <= 0.2 * rt.h);
}

TEST_CASE("contour: a pocket with 90 degree walls keeps its edges and corners", "[surface][contour]") {
    const Part part{kBox, {testing::boxCutter({Vec3(6.3, 7.7, 12.4), Vec3(25.6, 22.2, 30.0)})}};
    const Result r = contourPart(part, 1.0);
    INFO(summary("pocket", r));
    CHECK(r.check.ok());
    // Planes, edges and corners: exact up to the crossings' corner gap and float rounding.
    CHECK(r.faces.max <= 1e-3 * r.h);
}

TEST_CASE("contour: a 60 degree V-groove", "[surface][contour]") {
    // Walls at 30 degrees either side of the vertical through the groove's bottom line, which runs
    // along (1, 0.3, 0) at height 14.2.
    const Vec3 along = glm::normalize(Vec3(1.0, 0.3, 0.0)), across = glm::normalize(glm::cross(Vec3(0, 0, 1), along));
    const Vec3 bottom(16.0, 16.0, 14.2);
    const double s = std::sin(M_PI / 6), c = std::cos(M_PI / 6);
    const Vec3 n1 = c * across - s * Vec3(0, 0, 1), n2 = -c * across - s * Vec3(0, 0, 1);
    const Part part{kBox, {testing::halfSpaces({{n1, glm::dot(n1, bottom)}, {n2, glm::dot(n2, bottom)}})}};
    const Result r = contourPart(part, 1.0);
    INFO(summary("V-groove", r));
    CHECK(r.check.ok());
    // Measured: p99 0.0034 h, max 0.18 h where the groove leaves the block.
    CHECK(r.faces.p99 <= 5e-3 * r.h);
    CHECK(r.faces.max <= 0.25 * r.h);
}

TEST_CASE("contour: two crossing grooves leave a sharp spike", "[surface][contour]") {
    // Two 90 degree V-grooves crossing at 40 degrees: between them a wedge of material whose ridge
    // runs down to a spike where the grooves meet.
    auto groove = [](Vec3 along, Vec3 bottom) {
        along = glm::normalize(along);
        const Vec3 across = glm::normalize(glm::cross(Vec3(0, 0, 1), along));
        const double s = std::sin(M_PI / 4), c = std::cos(M_PI / 4);
        const Vec3 n1 = c * across - s * Vec3(0, 0, 1), n2 = -c * across - s * Vec3(0, 0, 1);
        return testing::halfSpaces({{n1, glm::dot(n1, bottom)}, {n2, glm::dot(n2, bottom)}});
    };
    const double a = 20.0 * M_PI / 180.0;
    const Part part{kBox, {groove(Vec3(std::cos(a), std::sin(a), 0), Vec3(16.1, 16.3, 17.7)),
                           groove(Vec3(std::cos(a), -std::sin(a), 0), Vec3(16.1, 16.3, 17.7))}};
    const Result r = contourPart(part, 1.0);
    INFO(summary("spike", r));
    CHECK(r.check.ok());
    // Measured: p99 0.010 h, max 0.23 h on the ridge running down to the spike (a convex crease,
    // kept within its crossings' box).
    CHECK(r.faces.p99 <= 0.02 * r.h);
    CHECK(r.faces.max <= 0.3 * r.h);
}

TEST_CASE("contour: a wall thinner than a cell", "[surface][contour]") {
    // Two pockets leave a wall 0.6 h thick around the lattice plane x = 15.5.
    const double h = 1.0;
    const Part part{kBox, {testing::boxCutter({Vec3(4.0, 5.2, 8.3), Vec3(15.23, 27.1, 30.0)}),
                           testing::boxCutter({Vec3(15.83, 5.2, 8.3), Vec3(28.0, 27.1, 30.0)})}};
    const Result r = contourPart(part, h);
    INFO(summary("thin wall", r));
    CHECK(r.check.ok());
    CHECK(r.faces.max <= 1e-3 * h);
}

TEST_CASE("contour: a wall thinner than a cell between two lattice planes is meshed from its dexels",
          "[surface][contour][fine]") {
    // The same pockets with the wall between x = 15.6 and 16.3: no lattice point (at 15.5 and
    // 16.5) lies in it, so the level set takes it as empty; its x dexels hold it, two ends on each
    // lattice edge across it, and the split cells mesh it. finerThanLattice counts it.
    const double h = 1.0, y0 = 5.2, y1 = 27.1, z0 = 8.3;
    const Part part{kBox, {testing::boxCutter({Vec3(4.0, y0, z0), Vec3(15.6, y1, 30.0)}),
                           testing::boxCutter({Vec3(16.3, y0, z0), Vec3(28.0, y1, 30.0)})}};
    TriDexelStock stock = TriDexelStock::fromBox(part.box, h);
    for (const Cutter& c : part.cuts) testing::carve(stock, c);
    const FineFeatures fine = finerThanLattice(stock);
    const Result r = contourPart(part, h);
    INFO(summary("wall between lattice planes", r) << "; " << r.stats.splitEdges << " split edges, "
         << r.stats.splitCells << " split cells, " << r.stats.faceVertices << " face vertices");
    CHECK(r.check.ok());
    const double across = (y1 - y0) * (kBox.hi.z - z0);
    const double wall = 0.7 * across, oneCut = kBox.volume() - (28.0 - 4.0) * across;
    CHECK(r.stats.splitEdges == 22 * 16);
    // The wall's top, the block's top face, lies above the last lattice plane, where no dexel
    // crosses the wall: there its height is the face rule's estimate, within a spacing. Measured:
    // 5.7 mm^3 short (the band allowed is 15.3), faces RMS 0.010 h, max 0.32 h on that top.
    const double unseenTop = 0.7 * (y1 - y0) * h;
    CHECK(r.check.signedVolume == Approx(oneCut + wall).margin(unseenTop));
    CHECK(r.faces.max <= 0.5 * h);
    CHECK(r.faces.rms <= 0.02 * h);
    CHECK(fine.material.count == 22 * 16);
    // The dexels' estimate: 0.7 mm per dexel, h^2 each, against the wall's exact volume.
    CHECK(fine.material.volumeMm3 == Approx(wall).epsilon(0.03));
}

TEST_CASE("contour: a slot narrower than a cell between two lattice planes is meshed from its dexels",
          "[surface][contour][fine]") {
    // A slot 0.4 mm wide between x = 15.6 and 16.0, through the top: no lattice point (at 15.5 and
    // 16.5) lies in it, so the level set fills it; its x dexels have a gap on each lattice edge
    // across it, and the split cells mesh it.
    const double h = 1.0, y0 = 5.2, y1 = 27.1, z0 = 8.3;
    const Part part{kBox, {testing::boxCutter({Vec3(15.6, y0, z0), Vec3(16.0, y1, 30.0)})}};
    const Result r = contourPart(part, h);
    INFO(summary("slot between lattice planes", r) << "; " << r.stats.splitEdges << " split edges");
    CHECK(r.check.ok());
    const double slot = 0.4 * (y1 - y0) * (kBox.hi.z - z0);
    // Its floor lies between lattice planes, where no dexel crosses the slot: its height there
    // is the face rule's estimate, within a spacing.
    CHECK(r.stats.splitEdges > 0);
    CHECK(r.check.signedVolume == Approx(kBox.volume() - slot).margin(0.4 * (y1 - y0) * h));
}

TEST_CASE("contour: a fin thinner than a cell that crosses cells slantwise keeps its patches apart",
          "[surface][contour][fine]") {
    // Two plunges of a flat end mill of radius 15 h whose walls pass 0.05 h apart, their centres
    // on a line 0.9 rad from x: the fin left between them is thinner than a cell and crosses the
    // corners of the cells' z faces slantwise. The face rule reads the fin's two ends in a cell as
    // two patches; one's vertex, fitted across the fin and bounded by the cell alone, sat on the
    // face below the other, and 16 pairs of fan triangles passed through each other (the bore's
    // wall of helical-thread-milling.gcode at h = 0.1 mm showed 3388). contourPart checks the
    // crossings.
    checkFinApart("slanting fin", finOfTwoPlunges(0.05, 0.9, Vec3(10.13, 10.64, 0.0)));
}

TEST_CASE("contour: a slanting fin that passes a lattice point closer than its lenses reach keeps its patches apart",
          "[surface][contour][fine]") {
    // As above, but the plunges' centres on a line 0.431412 rad from x and their walls 0.0259 h
    // apart at the neck: the fin passes 0.004 h from the lattice point (10.5, 9.5) and cuts the
    // corner of the z faces there, its sides crossing the x edge 0.004 and 0.071 h from it and the
    // y edge 0.008 and 0.178 h from it. The face rule read the two ends as two stubs, whose
    // lenses, at least a fifth of their chords deep (0.013 and 0.034 h), crossed each other near
    // the corner: 12 pairs of fan triangles passed through each other.
    checkFinApart("fin by a lattice point", finOfTwoPlunges(0.025918, 0.431412, Vec3(10.161619, 10.152137, 0.0)));
}

TEST_CASE("contour: a fin thinner than its walls' tangent planes overshoot keeps its sides apart",
          "[surface][contour][fine]") {
    // Plunges of radius 15 h whose walls pass 0.0136 h apart, their centres on a line 2.133 rad
    // from x: each side's crossings span a cell of a wall curved 1/15 per h, so their tangent
    // planes meet about h^2 / (8 * 15 h) = 0.008 h beyond it, in the fin, and the two sides'
    // vertices passed each other at the neck: 16 pairs of fan triangles passed through each other.
    checkFinApart("fin thinner than the overshoot", finOfTwoPlunges(0.013583, 2.133333, Vec3(10.219907, 9.883026, 0.0)));
}

TEST_CASE("contour: a fin between two ball plunges slanting across a cell keeps its lenses in their faces",
          "[surface][contour][fine]") {
    // Two ball plunges of radius 15 h whose surfaces pass 0.053 h apart at (9.74, 9.38, 1.35),
    // their centres on a line 0.873 rad from x and 0.158 rad below the xy plane: the fin between
    // them slants across the faces of the cell at (9.5, 8.5, 0.5). The two ends of its slice on an
    // edge of a face have normals within the feature angle of opposite, and their tangent lines,
    // turned toward each other by the walls' curvature, met past the face: taken for a wedge's
    // tip, the face vertex went to the far edge of the face z = 1.5, 0.999 h in, and 4 pairs of
    // fan triangles passed through each other (contourPart checks them).
    checkFinApart("fin between balls", finOfTwoBalls(0.053403, 0.872833, -0.157715, Vec3(9.737141, 9.380631, 1.345158)));
}

TEST_CASE("contour: a fin between two ball plunges that slants through a cell's face keeps its vertex off that face",
          "[surface][contour][fine]") {
    // Two ball plunges of radius 15 h whose surfaces pass 0.017 h apart at (9.06, 9.48, 1.37),
    // their centres on a line 1.389 rad from x and 0.565 rad below the xy plane: the fin between
    // them slants through the lattice plane z = 1.5 near the lattice point (9.5, 9.5, 1.5). Its
    // slice there ends on the y edge at x = 9.5 as a lens 0.5 h deep. A patch's vertex, clamped
    // onto that face, sat 0.004 h outside the lens; its fan over the lens lay in the face and
    // overlapped itself, and 3 pairs of triangles met (contourPart checks them).
    checkFinApart("fin through a face", finOfTwoBalls(0.016657, 1.389212, -0.564792, Vec3(9.058680, 9.477962, 1.369491)));
}

TEST_CASE("contour: split patches of one cell whose fans pass through each other are left to the table path",
          "[surface][contour][fine]") {
    // Two ball plunges of radius 15 h whose surfaces pass 0.024 h apart at (9.95, 9.41, 1.37),
    // their centres on a line 0.292 rad from x and 0.055 rad above the xy plane: the fin between
    // them meets the face y = 9.5 of the cell at (9.5, 8.5, 1.5) at x = 9.8 to 9.93. Of the two
    // patches the cell's loops make there, one's vertex sat at (10.07, 8.88, 2.00), the other's
    // at (9.93, 9.38, 1.63), and 4 pairs of their fan triangles passed through each other with
    // none folded. Such a cell's edges are now left to the table path, as a fold's are; no pair
    // is left (contourPart checks them).
    const Result res = finOfTwoBalls(0.023918, 0.292086, 0.055150, Vec3(9.952384, 9.406522, 1.372112));
    INFO(summary("fin between balls, fans crossing", res) << "; " << res.stats.splitEdges << " split edges");
    CHECK(res.check.ok());
    CHECK(res.stats.splitEdges > 0);  // the rest of the fin is meshed from its dexels
    CHECK(res.stats.splitEdgesDropped > 0);
}

TEST_CASE("contour: split cells that fold run after run are left to the table path 3 more times",
          "[surface][contour][fine]") {
    // A plate 0.0454 h thick through (9.0143, 10.8677, 1.3713), its normal 3.152 rad from x and
    // 0.5442 rad below the xy plane: it runs along y, and its dexels cross it on 44 edges with
    // several crossings. After repair one triangle of the first run's split cells still faces
    // against its vertices (none is folded by checkMesh's test), in the cells round four of those
    // edges, from (8.5, 5.5 and 6.5, 2.5) by the box's face y = 5. Left to the table path, they
    // make the split cells two further along y do the same at the next run, and those the next:
    // four edges a run. The fourth run, the last that kSplitRetries allows with split cells, has
    // none.
    const Result res = plate(0.0454, 3.1520, -0.5442, Vec3(9.0143, 10.8677, 1.3713));
    INFO(summary("plate folding three runs", res)
         << "; " << res.stats.splitRuns << " runs, " << res.stats.splitEdges << " split edges, "
         << res.stats.splitEdgesDropped << " dropped");
    CHECK(res.check.ok());
    CHECK(res.stats.splitRuns == 4);
    CHECK(res.stats.splitEdgesDropped == 12);
    CHECK(res.stats.splitEdges == 32);  // the rest of the plate is meshed from its dexels
}

TEST_CASE("contour: split cells that still fold after kSplitRetries runs are all left out",
          "[surface][contour][fine]") {
    // The plate of the test before, turned 0.005 rad less about z and 0.0014 rad less steep: its
    // faulty cells move along y as they did there, and the fourth run has them too (a fifth run
    // with split cells would as well, a sixth not). The fifth and last run finds no split cells and
    // makes what the level set alone shows: the bits of the plate round the two lattice points it
    // holds, (9.5, 13.5, 0.5) and (9.5, 14.5, 0.5), closed and without folds.
    const Result res = plate(0.0454, 3.1470, -0.5428, Vec3(9.0143, 10.8677, 1.3713));
    INFO(summary("plate folding four runs", res)
         << "; " << res.stats.splitRuns << " runs, " << res.stats.splitEdges << " split edges, "
         << res.stats.splitEdgesDropped << " dropped");
    CHECK(res.check.ok());
    CHECK(res.stats.splitRuns == 5);  // four with split cells, the last without
    CHECK(res.stats.splitEdges == 0);
    CHECK(res.stats.splitCells == 0);
    CHECK(res.stats.faceVertices == 0);
    CHECK(res.stats.splitEdgesDropped == 46);  // all that the first run found
}

TEST_CASE("contour: a fin's crease chords are not flipped through the other side of the fin",
          "[surface][contour][fine]") {
    // Two ball plunges of radius 5 h whose surfaces pass 0.0048 h apart at (9.48, 9.36, 1.06),
    // their centres on a line 2.311 rad from x and 0.388 rad above the xy plane: both sides of the
    // fin cross the cells at (7.5, 7.5, 1.5) and (8.5, 7.5, 1.5), each side a patch of the table's
    // loops. The flip pass joined one side's vertices, (8.499, 8.284, 1.503) and (9.161, 8.499,
    // 1.808), across the face x = 8.5 through the cells' insides, and 4 pairs of triangles met the
    // fans of the other side, 0.005 h away (contourPart checks them).
    checkFinApart("fin between small balls", finOfTwoBalls(0.004768, 2.311061, 0.387694, Vec3(9.483694, 9.360880, 1.064044), 5.0));
}

TEST_CASE("contour: the patches of a fin's cell that the face rule cut apart keep their fans apart",
          "[surface][contour][fine]") {
    // Two ball plunges of radius 5 h whose surfaces pass 0.0095 h apart at (9.21, 9.42, 1.08),
    // their centres on a line 2.500 rad from x and 0.346 rad below the xy plane: the fin between
    // them crosses the face z = 1.5 of the cell at (7.5, 7.5, 1.5) slantwise, and the asymptotic
    // decider cut its corner (8.5, 8.5, 1.5) off as a patch of its own. The other patch, holding
    // crossings of both sides, was fitted at (8.366, 8.499, 1.574), past that patch's chord on the
    // face y = 8.5, and 5 pairs of their fan triangles passed through each other, none folded
    // (contourPart checks them).
    checkFinApart("fin cut at a face", finOfTwoBalls(0.009517, 2.500465, -0.345721, Vec3(9.210257, 9.418062, 1.080355), 5.0));
}

TEST_CASE("contour: a split cell's vertex is kept off the faces its loop crosses", "[surface][contour][fine]") {
    // Two ball plunges of radius 2 h whose surfaces pass 0.024 h apart at (9.53, 9.07, 1.92): the
    // fin between them lies nearly in the lattice plane x = 9.5. The split cell beyond it had a
    // patch holding crossings of both sides, fitted past that face and clamped onto it at (9.5,
    // 8.932, 1.999), where the table path's vertex of the cell before it was clamped too: their
    // fans over the path they share overlapped in the face (3 pairs of triangles).
    checkFinApart("fin in a face", finOfTwoBalls(0.024073, 3.081145, 0.223876, Vec3(9.531458, 9.069396, 1.919947), 2.0));
    // Radius 2 h, 0.029 h apart at (9.38, 9.32, 1.79): a split cell's vertex clamped onto its
    // lattice edge x = y = 9.5, its fan lying in both faces through it over its paths there, where
    // the next cells' fans over those paths stand (8 pairs).
    checkFinApart("fin by an edge", finOfTwoBalls(0.028804, 2.409307, -0.110987, Vec3(9.375561, 9.317136, 1.789182), 2.0));
}

TEST_CASE("contour: ball passes closer than a cell", "[surface][contour]") {
    // Parallel passes of a ball of radius 3 mm at a stepover of 0.3 h: the cusps between them,
    // s^2 / (8 R) = 0.0009 mm high, are finer than the lattice can show.
    const double h = 0.5, step = 0.3 * h, r = 3.0;
    Part part{kBox, {}};
    for (double y = 8.0; y <= 24.0; y += step)
        part.cuts.push_back(testing::capsule(Vec3(6.0, y, 20.0 + r), Vec3(26.0, y, 20.0 + r), r));
    const Result res = contourPart(part, h);
    INFO(summary("ball passes", res));
    CHECK(res.check.ok());
    // Measured: RMS 0.0050 h, max 0.12 h where the passes end at the block's top face.
    CHECK(res.faces.rms <= 0.008 * h);
    CHECK(res.faces.max <= 0.2 * h);
}

TEST_CASE("contour: the error of a smooth surface falls at second order", "[surface][contour]") {
    // A spherical and a toroidal cavity inside the block: smooth surfaces without creases (the
    // block's own faces are exact and add nothing).
    for (const Cutter& cavity : {testing::sphere(Vec3(16.3, 15.8, 12.1), 8.0),
                                 testing::torus(Vec3(16.2, 15.9, 11.8), Vec3(0.2, -0.1, 1.0), 9.0, 4.0)}) {
        const Part part{kBox, {cavity}};
        double previous = 0.0;
        for (double h : {1.0, 0.5, 0.25}) {
            const Result r = contourPart(part, h);
            INFO(summary("cavity", r));
            CHECK(r.check.ok());
            if (previous > 0.0) {
                // Order 2 (vertices within O(h^2) of the surface), up to the sampling error of
                // 20,000 points: about 1 % on each RMS, 0.02 on the order. Measured: 2.00 to 2.08.
                const double order = std::log2(previous / r.faces.rms);
                INFO("order " << order);
                CHECK(order >= 1.95);
            }
            previous = r.faces.rms;
        }
    }
}

TEST_CASE("contour: a z-only stock still gives a closed mesh", "[surface][contour]") {
    const Part part{kBox, {testing::sphere(Vec3(16.3, 15.8, 30.1), 12.0),
                           testing::boxCutter({Vec3(3.3, 4.7, 9.4), Vec3(12.6, 11.2, 30.0)})}};
    for (const char* f : {"z", "x", "xy"}) {
        const Result r = contourPart(part, 1.0, FamilySet::parse(f));
        INFO(summary(f, r));
        CHECK(r.check.closedManifold());
        CHECK(r.check.degenerateTriangles == 0);
    }
}

TEST_CASE("contour: adaptivity merges flat regions and keeps the mesh closed", "[surface][contour]") {
    const Part part{kBox, {testing::boxCutter({Vec3(6.3, 7.7, 12.4), Vec3(25.6, 22.2, 30.0)}),
                           testing::sphere(Vec3(16.3, 15.8, 14.1), 5.0)}};
    TriDexelStock stock = TriDexelStock::fromBox(part.box, 1.0);
    for (const Cutter& c : part.cuts) testing::carve(stock, c);
    const LevelSet ls = rebuildLevelSet(stock);
    const Mesh full = contourStock(ls, stock);
    for (double adaptivity : {0.2, 1.0}) {
        ContourOptions o;
        o.adaptivity = adaptivity;
        ContourStats stats;
        const Mesh merged = contourStock(ls, stock, o, &stats);
        INFO("adaptivity " << adaptivity << ": " << merged.triangles.size() << " of " << full.triangles.size()
                           << " triangles; " << stats.check.foldedTriangles << " folded, "
                           << stats.check.degenerateTriangles << " degenerate, closed "
                           << stats.check.closedManifold());
        CHECK(stats.check.ok());
        CHECK(testing::countSelfIntersections(merged).pairs == 0);
        CHECK(stats.merged > 0);
        CHECK(merged.triangles.size() < full.triangles.size() / 4);
        // The surface moves by at most adaptivity * 0.05 h.
        const FaceDeviation d = measureFaces(merged, part, 3.0);
        CHECK(d.max <= measureFaces(full, part, 3.0).max + adaptivity * 0.05 + 1e-9);
    }
}

TEST_CASE("contour: the block's own faces, edges and corners are exact", "[surface][contour]") {
    // A size that is not a whole number of cells: the far faces fall anywhere between lattice
    // planes.
    const Box box{Vec3(-3.1, 2.05, 0.3), Vec3(9.37, 13.9, 7.77)};
    const Part part{box, {}};
    const Result r = contourPart(part, 0.7);
    INFO(summary("block", r));
    CHECK(r.check.ok());
    CHECK(r.stats.cornerVertices == 8);
    // Exact up to the dexels' float endpoints: about 6e-8 of the distance from the lattice origin.
    CHECK(r.faces.max <= 1e-6);
    CHECK(r.check.signedVolume == Approx(box.volume()).epsilon(1e-7));
}

TEST_CASE("contour: surfaces that graze lattice points stand no triangle on edge", "[surface][contour]") {
    // A spherical void whose surface passes a micrometre from a lattice point, with its normal
    // there nearly across a lattice axis, makes a cell whose loop is a sliver: two crossings
    // next to the lattice point and one a cell away. The least-squares vertex of such a loop
    // lies off its (nearly degenerate) plane, and its fan would stand on edge over the sliver.
    // Every triangle on the sphere must face within 80 degrees of the sphere's normal: the fan
    // keeps within 60 degrees of its crossings' mean normal, which is within half the feature
    // angle (17 degrees) of the surface's.
    const double h = 1.0;
    const Box box{Vec3(0.0), Vec3(16.0)};
    const double kDegree = 3.14159265358979323846 / 180.0;
    const double minCosine = std::cos(80.0 * kDegree);
    std::mt19937 rng(20261124);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::uniform_int_distribution<int> lattice(6, 9);
    std::size_t onEdge = 0, checked = 0;
    std::string first;
    for (int n = 0; n < 80; ++n) {
        const double r = 2.0 + 0.5 * (unit(rng) + 1.0);
        // The lattice point (i + 1/2) h, and the sphere's normal there: random, or across axis n % 3.
        const Vec3 p = (Vec3(lattice(rng), lattice(rng), lattice(rng)) + 0.5) * h;
        Vec3 d(unit(rng), unit(rng), unit(rng));
        if (n % 2 == 0) d[n % 3] = 1e-3 * unit(rng);
        d = glm::normalize(d);
        const Vec3 centre = p + (r + 1e-6 * unit(rng)) * d;
        const Part part{box, {testing::sphere(centre, r)}};
        const Result res = contourPart(part, h);
        CHECK(res.check.ok());
        for (const Mesh::Triangle& t : res.mesh.triangles) {
            const Vec3 a = res.mesh.vertices[t[0]], b = res.mesh.vertices[t[1]], c = res.mesh.vertices[t[2]];
            const Vec3 mid = (a + b + c) / 3.0;
            if (glm::length(mid - centre) > r + 0.5 * h) continue;  // on the block's faces
            const Vec3 area = glm::cross(b - a, c - a);
            const Vec3 outward = -part.cuts[0].normal(mid);  // out of the material: into the void
            ++checked;
            if (glm::dot(area, outward) < minCosine * glm::length(area) && onEdge++ == 0) {
                std::ostringstream out;
                out << "first: sphere " << n << " (centre " << centre.x << ", " << centre.y << ", " << centre.z
                    << ", radius " << r << "), triangle at (" << mid.x << ", " << mid.y << ", " << mid.z << ") faces "
                    << std::acos(glm::dot(area, outward) / glm::length(area)) / kDegree << " degrees from the surface";
                first = out.str();
            }
        }
    }
    INFO(checked << " triangles on the spheres; " << onEdge << " on edge; " << first);
    CHECK(checked > 0);
    CHECK(onEdge == 0);
}

TEST_CASE("contour: the mesh does not depend on the grid's index offset", "[surface][contour]") {
    // The same triangles, listed in another order: the blocks move, the lattice does not. Three
    // families and z alone (whose walls come from neighbouring dexels); offsets 0, chosen, and
    // random (fixed seed).
    const Part part{kBox,
                    {testing::sphere(Vec3(16.3, 15.8, 30.1), 12.0),
                     testing::boxCutter({Vec3(3.3, 4.7, 10.4), Vec3(12.6, 28.2, 30.0)}),
                     testing::halfSpaces({{glm::normalize(Vec3(0.3, 0.2, -1.0)), -20.0}})}};
    std::mt19937 rng(8);
    std::uniform_int_distribution<int> phase(0, 7);
    for (const FamilySet families : {FamilySet::all(), FamilySet::parse("z")}) {
        std::vector<Mesh> meshes;
        for (const std::optional<std::array<int, 3>>& offset :
             {std::optional<std::array<int, 3>>{std::array<int, 3>{0, 0, 0}}, std::optional<std::array<int, 3>>{},
              std::optional<std::array<int, 3>>{std::array<int, 3>{phase(rng), phase(rng), phase(rng)}}}) {
            const Result r = contourPart(part, 1.0, families, offset);
            CHECK(r.check.ok());
            meshes.push_back(r.mesh);
        }
        auto corners = [](const Mesh& m) {
            std::vector<std::array<Vec3, 3>> out;
            for (std::size_t t : testing::surfaceOrder(m)) {
                const Mesh::Triangle& tri = m.triangles[t];
                out.push_back({m.vertices[tri[0]], m.vertices[tri[1]], m.vertices[tri[2]]});
            }
            return out;
        };
        const auto first = corners(meshes[0]);
        INFO("families " << families.str() << ", " << first.size() << " triangles");
        CHECK(first.size() > 5000);
        for (std::size_t k = 1; k < meshes.size(); ++k) {
            const auto other = corners(meshes[k]);
            REQUIRE(other.size() == first.size());
            std::size_t differ = 0;
            for (std::size_t t = 0; t < first.size(); ++t) {
                // Corners in the order surfaceOrder turned them to.
                const auto& a = first[t];
                const auto& b = other[t];
                bool same = false;
                for (int r = 0; r < 3 && !same; ++r) same = a[0] == b[std::size_t(r)] && a[1] == b[std::size_t((r + 1) % 3)] &&
                                                             a[2] == b[std::size_t((r + 2) % 3)];
                differ += !same;
            }
            CHECK(differ == 0);
        }
    }
}

TEST_CASE("contour: a block cut away entirely gives an empty mesh", "[surface][contour]") {
    // The level set has no leaf: no block holds a cell with surface.
    const Part part{kBox, {testing::boxCutter({Vec3(-1.0), kBox.hi + 1.0})}};
    const Result r = contourPart(part, 1.0);
    CHECK(r.mesh.vertices.empty());
    CHECK(r.mesh.triangles.empty());
    CHECK(r.stats.cells == 0);
    CHECK(r.check.triangleCount == 0);
    CHECK(r.check.boundaryEdges == 0);
    CHECK(r.faces.samples == 0);
}
