// The machined surface against the design: a sphere's mesh measured against a cube, whose signed
// distance is known in closed form, so every vertex's distance, the areas and the histogram have
// analytic answers. Then the same through the compare job (files in, report, PLY and picture out)
// and through the simulate job.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "dexelmill/compare/deviation.h"
#include "dexelmill/compare/design.h"
#include "dexelmill/error.h"
#include "dexelmill/io/mesh_io.h"
#include "dexelmill/job/compare.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/tool/builders.h"
#include "support/scratch.h"

using namespace dexelmill;
namespace fs = std::filesystem;

namespace {

/// A sphere of radius r about the origin: an octahedron subdivided `levels` times, every vertex
/// pushed onto the sphere. Closed, facing out.
Mesh sphere(double r, int levels) {
    Mesh m;
    m.vertices = {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0, 0, 1), Vec3(0, 0, -1)};
    m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
        auto middle = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::minmax(a, b);
            const auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            m.vertices.push_back(glm::normalize(m.vertices[a] + m.vertices[b]));
            return mid[key] = std::uint32_t(m.vertices.size() - 1);
        };
        decltype(m.triangles) next;
        for (const auto& t : m.triangles) {
            const std::uint32_t ab = middle(t[0], t[1]), bc = middle(t[1], t[2]), ca = middle(t[2], t[0]);
            next.push_back({t[0], ab, ca});
            next.push_back({ab, t[1], bc});
            next.push_back({ca, bc, t[2]});
            next.push_back({ab, bc, ca});
        }
        m.triangles = next;
    }
    for (Vec3& v : m.vertices) v = r * glm::normalize(v);
    return m;
}

/// The cube [-h, h]^3 as 12 triangles facing out.
Mesh cube(double h) {
    Mesh m;
    for (int i = 0; i < 8; ++i) m.vertices.emplace_back(i & 1 ? h : -h, i & 2 ? h : -h, i & 4 ? h : -h);
    const std::uint32_t f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : f) {
        m.triangles.push_back({q[0], q[1], q[2]});
        m.triangles.push_back({q[0], q[2], q[3]});
    }
    return m;
}

/// A prism: the polygon `profile` (counter-clockwise in the x-z plane, x right, z up) between
/// y = 0 and y = length, its caps the triangles `caps` (indices into the profile, counter-clockwise
/// too). Closed, facing out.
Mesh prism(const std::vector<std::pair<double, double>>& profile, const std::vector<std::array<std::uint32_t, 3>>& caps,
           double length) {
    Mesh m;
    const std::uint32_t n = std::uint32_t(profile.size());
    for (const double y : {0.0, length})
        for (const auto& [x, z] : profile) m.vertices.emplace_back(x, y, z);
    for (const auto& t : caps) {
        m.triangles.push_back({t[0], t[1], t[2]});              // y = 0, facing -y
        m.triangles.push_back({n + t[0], n + t[2], n + t[1]});  // y = length, facing +y
    }
    for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint32_t j = (i + 1) % n;
        m.triangles.push_back({i, n + i, n + j});
        m.triangles.push_back({i, n + j, j});
    }
    return m;
}

/// The cube's signed distance in closed form: outside, the length of the excess over the faces;
/// inside, minus the distance to the nearest face.
double cubeDistance(const Vec3& p, double h) {
    const Vec3 q = glm::abs(p) - Vec3(h);
    return glm::length(glm::max(q, Vec3(0.0))) + std::min(std::max({q.x, q.y, q.z}), 0.0);
}

double triangleArea(const Mesh& m, const std::array<std::uint32_t, 3>& t) {
    return 0.5 * glm::length(glm::cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]));
}

double meshArea(const Mesh& m) {
    double a = 0.0;
    for (const auto& t : m.triangles) a += triangleArea(m, t);
    return a;
}

/// The least distance from the origin of a triangle's plane: no point of the mesh lies nearer.
double innerRadius(const Mesh& m) {
    double r = std::numeric_limits<double>::infinity();
    for (const auto& t : m.triangles) {
        const Vec3 n = glm::normalize(glm::cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]));
        r = std::min(r, std::abs(glm::dot(n, m.vertices[t[0]])));
    }
    return r;
}

/// A mesh's distances to the cube [-h, h]^3 in closed form, each triangle cut into kCuts^2 copies
/// of itself measured at their centroids: every point lies within `own` of its copy's centroid.
class Oracle {
public:
    static constexpr int kCuts = 32;
    double own = 0.0;

    Oracle(const Mesh& m, double h) {
        for (const auto& t : m.triangles) {
            const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
            const Vec3 u = (b - a) / double(kCuts), v = (c - a) / double(kCuts);
            // A centroid lies 2/3 of a median, at most 2/3 of the longest edge, from a corner.
            own = std::max(own, 2.0 / 3.0 * std::max({glm::length(u), glm::length(v), glm::length(v - u)}));
            const double piece = triangleArea(m, t) / double(kCuts * kCuts);
            for (int i = 0; i < kCuts; ++i)
                for (int j = 0; i + j < kCuts; ++j) {
                    const Vec3 corner = a + double(i) * u + double(j) * v;
                    samples_.push_back({cubeDistance(corner + (u + v) / 3.0, h), piece});  // upright
                    if (i + j + 1 < kCuts)  // and the copy upside down beside it
                        samples_.push_back({cubeDistance(corner + 2.0 * (u + v) / 3.0, h), piece});
                }
        }
    }
    /// The area whose distance lies in [from, to].
    double area(double from, double to) const {
        double a = 0.0;
        for (const auto& [d, w] : samples_)
            if (d >= from && d <= to) a += w;
        return a;
    }
    /// The area-weighted RMS distance.
    double rms() const {
        double sum2 = 0.0, a = 0.0;
        for (const auto& [d, w] : samples_) sum2 += w * d * d, a += w;
        return std::sqrt(sum2 / a);
    }

private:
    std::vector<std::pair<double, double>> samples_;  ///< (distance, area)
};

std::string asciiStl(const Mesh& m) {
    std::ostringstream s;
    s.precision(17);
    s << "solid cube\n";
    for (const auto& t : m.triangles) {
        s << " facet normal 0 0 0\n  outer loop\n";
        for (std::uint32_t v : t) s << "   vertex " << m.vertices[v].x << " " << m.vertices[v].y << " " << m.vertices[v].z << "\n";
        s << "  endloop\n endfacet\n";
    }
    s << "endsolid cube\n";
    return s.str();
}

fs::path scratch(const std::string& name) { return testing::scratchFolder("dexelmill_test_deviation_", name); }

// A sphere of radius 5.9 against the cube of half-side 5: it bulges 0.9 mm out through each face's
// middle (where the meshes below have vertices), and its points along the diagonals lie
// 5 - 5.9 / sqrt(3) = 1.594 mm inside (the meshes' vertices nearest them a little less).
constexpr double kRadius = 5.9, kHalf = 5.0;

/// The oracle's deepest and farthest vertex of a mesh against the cube.
std::pair<double, double> cubeExtremes(const Mesh& m) {
    double lo = 0.0, hi = 0.0;
    for (const Vec3& v : m.vertices) {
        lo = std::min(lo, cubeDistance(v, kHalf));
        hi = std::max(hi, cubeDistance(v, kHalf));
    }
    return {lo, hi};
}

}  // namespace

TEST_CASE("deviation: every vertex's signed distance, the areas and the histogram, in closed form",
          "[compare][deviation]") {
    const Mesh machined = sphere(kRadius, 4);
    const MeshDistance design{cube(kHalf)};
    const DeviationTolerance tol{0.01, 0.05};
    const Deviation d = measureDeviation(machined, design, tol);
    REQUIRE(d.distance.size() == machined.vertices.size());
    double lo = 0, hi = 0;
    for (std::size_t i = 0; i < machined.vertices.size(); ++i) {
        const double expected = cubeDistance(machined.vertices[i], kHalf);
        INFO("vertex " << i);
        CHECK(d.distance[i] == Approx(expected).margin(1e-12));
        lo = std::min(lo, expected);
        hi = std::max(hi, expected);
    }
    // Outside the cube the distance is a convex function, largest at a triangle's corners: the
    // farthest point is a vertex on an axis. Inside, points between the vertices may lie deeper,
    // but no point at r from the centre lies deeper than r / sqrt(3) - kHalf (the diagonals).
    CHECK(d.farthest == Approx(hi).margin(1e-12));
    CHECK(d.farthest == Approx(kRadius - kHalf).margin(1e-12));
    CHECK(d.deepest <= lo + 1e-12);
    CHECK(d.deepest >= innerRadius(machined) / std::sqrt(3.0) - kHalf);
    CHECK(cubeDistance(d.deepestPoint, kHalf) == Approx(d.deepest));
    CHECK(d.area == Approx(meshArea(machined)).epsilon(1e-9));  // a sum of a million shares

    // The oracle: the areas by distance from the closed form at many more points. A measured
    // point stands for surface within the spacing of it, and the oracle's for surface within
    // `own`; so the two may differ only on surface whose distance lies within `band` of a class's
    // edge, and by at most the oracle's area there.
    const Oracle oracle(machined, kHalf);
    const double band = d.spacing + 2.0 * oracle.own;
    const auto between = [&](double from, double to) { return oracle.area(from, to); };
    const auto near = [&](double edge) { return oracle.area(edge - band, edge + band); };
    const double deep = -10.0, far = 10.0;
    CHECK(d.gougeArea == Approx(between(deep, -tol.gouge)).margin(near(-tol.gouge)));
    CHECK(d.excessArea == Approx(between(tol.excess, far)).margin(near(tol.excess)));
    CHECK(d.withinArea == Approx(between(-tol.gouge, tol.excess)).margin(near(-tol.gouge) + near(tol.excess)));
    CHECK(d.rms == Approx(oracle.rms()).margin(band));
    CHECK(d.gougeArea > 0.0);
    CHECK(d.excessArea > 0.0);

    // Bins: -2 (the deepest is 1.23 to 1.6 mm) .. -1 .. -0.5 .. -0.2 .. -0.1 .. -0.05 .. -0.02 ..
    // -0.01, within to +0.05, then 0.1, 0.25, 0.5, 1 (the farthest, 0.9 mm, lies in the last).
    REQUIRE(lo < -1.0);
    const std::vector<double> edges{-2, -1, -0.5, -0.2, -0.1, -0.05, -0.02, -0.01, 0.05, 0.1, 0.25, 0.5, 1.0};
    REQUIRE(d.histogram.size() == edges.size() - 1);
    double binned = 0.0;
    std::size_t points = 0;
    for (std::size_t b = 0; b < d.histogram.size(); ++b) {
        const DeviationBin& bin = d.histogram[b];
        INFO("bin " << bin.lo << " .. " << bin.hi);
        CHECK(bin.lo == Approx(edges[b]).epsilon(1e-12));
        CHECK(bin.hi == Approx(edges[b + 1]).epsilon(1e-12));
        CHECK(bin.area == Approx(between(bin.lo, bin.hi)).margin(near(bin.lo) + near(bin.hi)));
        binned += bin.area;
        points += bin.points;
    }
    CHECK(binned == Approx(d.area).epsilon(1e-9));
    CHECK(points > machined.vertices.size());
    // The points inside the triangles number at most the vertices or 2^16, whichever is more.
    CHECK(points - machined.vertices.size() <= std::max<std::size_t>(machined.vertices.size(), 1 << 16));
}

TEST_CASE("deviation: an uncut block against a slotted design finds the slot between its vertices",
          "[compare][deviation]") {
    // The design: a 50 x 50 x 20 mm block with a slot 10 mm wide (x 20 .. 30) and 5 mm deep along
    // y. The machined part: the uncut block, 12 triangles whose vertices all lie on the design.
    // Its top face over the slot lies min(x - 20, 30 - x, 5) outside the design, and so do the
    // ends of its end faces over the slot, min(x - 20, 30 - x, z - 15): excess beyond 0.05 mm on
    // 9.9 x 50 mm of the top and 9.9 x 4.95 mm of each end. Everything else lies on the design.
    const Mesh block = prism({{0, 0}, {50, 0}, {50, 20}, {0, 20}}, {{0, 1, 2}, {0, 2, 3}}, 50.0);
    const Mesh slotted = prism({{0, 0}, {50, 0}, {50, 20}, {30, 20}, {30, 15}, {20, 15}, {20, 20}, {0, 20}},
                               {{0, 1, 4}, {1, 2, 3}, {1, 3, 4}, {0, 4, 5}, {0, 5, 6}, {0, 6, 7}}, 50.0);
    const MeshDistance design(slotted);
    REQUIRE(design.orientation() == 1);
    const DeviationTolerance tol{0.01, 0.05};
    const Deviation d = measureDeviation(block, design, tol);
    for (double v : d.distance) CHECK(std::abs(v) <= 1e-6);  // every vertex is on the design

    const double area = 2 * 50 * 20 + 2 * 50 * 50 + 2 * 20 * 50;
    const double excess = 9.9 * 50 + 2 * 9.9 * 4.95;
    CHECK(d.area == Approx(area).epsilon(1e-12));
    // A measured point stands for the surface within about the spacing of it: only along the
    // lines where the class changes (2 x 50 mm on the top, the rims of the two 9.9 x 4.95 mm
    // rectangles) may a point's class differ from its neighbourhood's.
    REQUIRE(d.spacing > 0.0);
    REQUIRE(d.spacing < 1.0);
    const double lines = 2 * 50 + 2 * 2 * (9.9 + 4.95);
    const double margin = 2.0 * d.spacing * lines;
    CHECK(d.excessArea == Approx(excess).margin(margin));
    CHECK(d.withinArea == Approx(area - excess).margin(margin));
    CHECK(d.gougeArea == 0.0);
    CHECK(d.withinArea < 0.95 * d.area);
    // The farthest point is the slot's middle, 5 mm from its walls and its floor.
    CHECK(d.farthest <= 5.0 + 1e-9);
    CHECK(d.farthest >= 5.0 - d.spacing / std::sqrt(3.0));
    CHECK(d.deepest >= -1e-9);
}

TEST_CASE("deviation: the RMS of a box 0.125 mm low, worked out by hand, whatever the tolerances",
          "[compare][deviation]") {
    // The part: the box [0, 10]^3, 12 right isosceles triangles. The design: the same box with its
    // top at z = 9.875. The part's top lies 0.125 mm outside the design (100 mm^2); each of its
    // four sides lies z - 9.875 outside it for z > 9.875 (the design's top edge is nearest), and on
    // it below. So the integral of d^2 is 100 x 0.125^2 + 4 x 10 x 0.125^3 / 3 = 1.5625 +
    // 0.0260417 = 1.5885417 mm^4 over 600 mm^2: the RMS is 0.0514545 mm.
    const Mesh part = prism({{0, 0}, {10, 0}, {10, 10}, {0, 10}}, {{0, 1, 2}, {0, 2, 3}}, 10.0);
    const MeshDistance design(prism({{0, 0}, {10, 0}, {10, 9.875}, {0, 9.875}}, {{0, 1, 2}, {0, 2, 3}}, 10.0));
    const double top = 100.0 * 0.125 * 0.125, sides = 40.0 * std::pow(0.125, 3) / 3.0;
    const double exact = std::sqrt((top + sides) / 600.0);
    REQUIRE(exact == Approx(0.0514545).epsilon(1e-6));

    // The tolerances only class the points: the sampling, so the RMS, is the same for any.
    const Deviation d = measureDeviation(part, design, {0.01, 0.05});
    for (const DeviationTolerance tol : {DeviationTolerance{0.0, 0.0}, DeviationTolerance{0.25, 0.25}, DeviationTolerance{1.0, 0.1}}) {
        const Deviation other = measureDeviation(part, design, tol);
        CHECK(other.spacing == d.spacing);
        CHECK(other.rms == d.rms);
    }
    // The triangles take the lattice: copies with legs l = 10 / k, k = ceil(10 sqrt(2) / s), legs
    // along z and across it. d^2 = ((z - 9.875)+)^2 is convex, so the mean of its values at a
    // copy's corners is at least its mean over the copy; and z^2 - d^2 is convex too, so it
    // exceeds it by at most z^2's excess, (sum of the squared differences of the corners' z) / 12
    // = l^2 / 6. Only copies above z = 9.875 - l see d^2 > 0: the measured integral lies between
    // the exact one and it plus 40 (0.125 + l) l^2 / 6, and the top is exact.
    const double l = 10.0 / std::ceil(10.0 * std::sqrt(2.0) / d.spacing);
    REQUIRE(l < 0.125);
    const double highest = std::sqrt((top + sides + 40.0 * (0.125 + l) * l * l / 6.0) / 600.0);
    CHECK(d.rms >= exact * (1.0 - 1e-12));
    CHECK(d.rms <= highest);
    CHECK(highest < 1.01 * exact);
}

TEST_CASE("deviation: a part that lies on the design measures 0 everywhere, not rounding",
          "[compare][deviation][degenerate]") {
    // The cube turned about a skew axis and moved far from the origin, its faces cut into 16
    // triangles each: the new vertices lie on the design's faces but not at its corners, and
    // their distances come out as rounding (a few units in the last place of 2000 mm) unless
    // taken as 0.
    const Vec3 axis = glm::normalize(Vec3(1, 2, 3)), offset(1000.1, -2000.3, 500.7);
    const double angle = 0.7;
    Mesh design = cube(kHalf);
    for (Vec3& v : design.vertices)  // Rodrigues' rotation, then the offset
        v = v * std::cos(angle) + glm::cross(axis, v) * std::sin(angle) + axis * glm::dot(axis, v) * (1.0 - std::cos(angle)) + offset;
    Mesh part = design;
    for (int level = 0; level < 2; ++level) {
        Mesh finer;
        finer.vertices = part.vertices;
        for (const auto& t : part.triangles) {
            std::uint32_t mid[3];
            for (std::size_t k = 0; k < 3; ++k) {
                finer.vertices.push_back(0.5 * (part.vertices[t[k]] + part.vertices[t[(k + 1) % 3]]));
                mid[k] = std::uint32_t(finer.vertices.size() - 1);
            }
            finer.triangles.push_back({t[0], mid[0], mid[2]});
            finer.triangles.push_back({mid[0], t[1], mid[1]});
            finer.triangles.push_back({mid[2], mid[1], t[2]});
            finer.triangles.push_back({mid[0], mid[1], mid[2]});
        }
        part = finer;
    }
    const Deviation d = measureDeviation(part, MeshDistance(design), {0.0, 0.0});
    for (double v : d.distance) CHECK(v == 0.0);
    CHECK(d.deepest == 0.0);
    CHECK(d.farthest == 0.0);
    CHECK(d.rms == 0.0);
    REQUIRE(d.histogram.size() == 1);
    CHECK(d.withinArea == Approx(600.0));
}

TEST_CASE("compare: a slot only the points between the vertices find is named, since the colours cannot show it",
          "[compare][deviation][job]") {
    // The uncut block and the slotted design of the test above, as files.
    const fs::path dir = scratch("hidden");
    writeStl((dir / "block.stl").string(), prism({{0, 0}, {50, 0}, {50, 20}, {0, 20}}, {{0, 1, 2}, {0, 2, 3}}, 50.0));
    writeStl((dir / "slotted.stl").string(),
             prism({{0, 0}, {50, 0}, {50, 20}, {30, 20}, {30, 15}, {20, 15}, {20, 20}, {0, 20}},
                   {{0, 1, 4}, {1, 2, 3}, {1, 3, 4}, {0, 4, 5}, {0, 5, 6}, {0, 6, 7}}, 50.0));
    CompareOptions o;
    o.machinedPath = (dir / "block.stl").string();
    o.designPath = (dir / "slotted.stl").string();
    o.tolerance = {0.01, 0.05};
    const auto hiddenWarnings = [](const CompareReport& r) {
        return std::count_if(r.warnings.begin(), r.warnings.end(), [](const std::string& w) {
            return w.find("between the mesh's vertices") != std::string::npos;
        });
    };
    // Without a picture or a PLY nothing is hidden.
    CHECK(hiddenWarnings(compareParts(o)) == 0);
    o.plyPath = (dir / "deviation.ply").string();
    const CompareReport r = compareParts(o);
    REQUIRE(hiddenWarnings(r) == 1);
    // The excess reaches 5 mm in the slot's middle; the sampling finds it to within its bound.
    const std::string lead = "the excess found between the mesh's vertices (up to ";
    REQUIRE_THAT(r.warnings.back(), Catch::StartsWith(lead) && Catch::Contains(" mm) does not show in the picture"));
    const double found = std::stod(r.warnings.back().substr(lead.size()));
    CHECK(found <= 5.0);
    CHECK(found >= 5.0 - r.deviation.spacing / std::sqrt(3.0) - 0.001);  // printed to 4 digits
}

TEST_CASE("deviation: zero tolerances, a surface that matches, and the colours", "[compare][deviation][degenerate]") {
    // The cube against itself: every vertex on the design, one bin, all within tolerance.
    const Mesh c = cube(kHalf);
    const Deviation same = measureDeviation(c, MeshDistance(c), {0.0, 0.0});
    CHECK(same.deepest == 0.0);
    CHECK(same.farthest == 0.0);
    REQUIRE(same.histogram.size() == 1);
    CHECK(same.histogram[0].points > 8);
    CHECK(same.withinArea == Approx(6 * 100.0));

    // Zero tolerances step the bins in micrometres: 0, 1, 2, 5, 10 ... 1000 or 2000 um (the
    // deepest vertex of this coarser sphere is 0.83 mm inside, points between them deeper, but
    // less than 2 mm: no point at r from the centre is deeper than r / sqrt(3) - kHalf).
    const Mesh coarse = sphere(kRadius, 2);
    const auto [deepest, farthest] = cubeExtremes(coarse);
    REQUIRE(deepest < -0.5);
    REQUIRE(innerRadius(coarse) / std::sqrt(3.0) - kHalf > -2.0);
    const Deviation d = measureDeviation(coarse, MeshDistance(c), {0.0, 0.0});
    CHECK(d.deepest <= deepest);
    CHECK(d.histogram.front().lo == Approx(d.deepest < -1.0 ? -2.0 : -1.0));
    CHECK(d.histogram.back().hi == Approx(1.0));
    const auto within = std::find_if(d.histogram.begin(), d.histogram.end(), [](const DeviationBin& b) { return b.lo == 0.0 && b.hi == 0.0; });
    REQUIRE(within != d.histogram.end());
    CHECK((within + 1)->hi == Approx(0.001));
    CHECK((within - 1)->lo == Approx(-0.001));

    // Colours: green within, reds below (darker deeper), blues above (darker farther).
    const Deviation measured = measureDeviation(coarse, MeshDistance(c), {0.01, 0.05});
    const DeviationScale scale = deviationScale(measured);
    CHECK(scale.excessFull == Approx(farthest));
    CHECK(scale.gougeFull == Approx(-measured.deepest));
    const Rgb green = deviationColour(0.0, scale), shallow = deviationColour(-0.02, scale),
              deep = deviationColour(-1.5, scale), near = deviationColour(0.06, scale), far = deviationColour(0.9, scale);
    CHECK(deviationColour(-0.01, scale) == green);
    CHECK(deviationColour(0.05, scale) == green);
    CHECK((green[1] > green[0] && green[1] > green[2]));
    CHECK((shallow[0] > shallow[2] && deep[0] > deep[2]));
    CHECK(deep[1] < shallow[1]);
    CHECK((near[2] > near[0] && far[2] > far[0]));
    CHECK(far[0] < near[0]);
    CHECK(deviationColour(-100.0, scale) == deviationColour(-scale.gougeFull, scale));

    // The legend: red at the bottom, green in the middle, blue at the top, labelled in mm.
    const PictureLegend legend = deviationLegend({{0.01, 0.05}, 0.828, 0.9});
    REQUIRE(legend.bar.size() % 3 == 0);
    CHECK(legend.bar[legend.bar.size() / 2] == green);
    CHECK(legend.bar.front()[0] > legend.bar.front()[2]);
    CHECK(legend.bar.back()[2] > legend.bar.back()[0]);
    std::vector<std::string> texts;
    for (const auto& l : legend.labels) texts.push_back(l.text);
    CHECK(texts == std::vector<std::string>{"-0.828", "gouge", "-0.01", "within", "+0.05", "excess", "+0.9"});
    // Tolerances of a few micrometres and zero print as decimals, never with an exponent.
    texts.clear();
    for (const auto& l : deviationLegend({{0.0, 0.00001}, 0.0002, 12345.6}).labels) texts.push_back(l.text);
    CHECK(texts == std::vector<std::string>{"-0.0002", "gouge", "0", "within", "+0.00001", "excess", "+12346"});
}

TEST_CASE("compare: a sphere's STL against a cube's, with report, PLY and picture", "[compare][deviation][job]") {
    const fs::path dir = scratch("files");
    const Mesh machined = sphere(kRadius, 4);
    writeStl((dir / "sphere.stl").string(), machined);
    std::ofstream(dir / "cube.stl") << asciiStl(cube(kHalf));
    CompareOptions o;
    o.machinedPath = (dir / "sphere.stl").string();
    o.designPath = (dir / "cube.stl").string();
    o.plyPath = (dir / "deviation.ply").string();
    o.pngPath = (dir / "deviation.png").string();
    o.reportPath = (dir / "report.json").string();
    o.threads = 2;
    const CompareReport r = compareParts(o);
    CHECK(r.machinedClosed);
    CHECK(r.machinedTriangles == machined.triangles.size());
    CHECK(r.designTriangles == 12);
    CHECK(r.designClosed);
    CHECK(r.warnings.empty());
    // Written as float, the sphere's vertices move by up to 6e-8 * 6 mm.
    CHECK(r.deviation.farthest == Approx(kRadius - kHalf).margin(1e-6));
    CHECK(r.deviation.deepest <= cubeExtremes(machined).first + 1e-6);
    CHECK(r.deviation.deepest >= innerRadius(machined) / std::sqrt(3.0) - kHalf - 1e-6);

    const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "report.json"));
    CHECK(j["units"] == "mm");
    CHECK(j["design"]["closed"] == true);
    CHECK(j["warnings"].empty());
    CHECK(j["surface"]["farthest_mm"].get<double>() == Approx(kRadius - kHalf).margin(1e-6));
    CHECK(j["surface"]["histogram"].size() == r.deviation.histogram.size());
    CHECK(j["surface"]["sample_spacing_mm"].get<double>() == r.deviation.spacing);
    CHECK(r.deviation.spacing > 0.0);
    double binned = 0;
    for (const auto& b : j["surface"]["histogram"]) binned += b["area_mm2"].get<double>();
    CHECK(binned == Approx(j["surface"]["area_mm2"].get<double>()));

    // The PLY: its header names the colours and the distance, and the sizes add up.
    std::ifstream ply(dir / "deviation.ply", std::ios::binary);
    std::string header, line;
    while (std::getline(ply, line) && line != "end_header") header += line + "\n";
    CHECK(header.find("element vertex " + std::to_string(machined.vertices.size())) != std::string::npos);
    CHECK(header.find("property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float deviation_mm\n") != std::string::npos);
    const auto headerBytes = std::size_t(ply.tellg());
    CHECK(fs::file_size(dir / "deviation.ply") ==
          headerBytes + machined.vertices.size() * (12 + 3 + 4) + machined.triangles.size() * 13);
    CHECK(fs::file_size(dir / "deviation.png") > 1000);

    // Errors: an unknown format, a bad tolerance, a report that is not JSON; nothing written.
    CompareOptions bad = o;
    bad.machinedPath = (dir / "sphere.obj").string();
    CHECK_THROWS_WITH(compareParts(bad), Catch::Contains("must be an STL file (.stl) or a level set (.vdb)"));
    bad = o;
    bad.tolerance.gouge = -1.0;
    CHECK_THROWS_WITH(compareParts(bad), Catch::Contains("tolerances"));
    bad = o;
    bad.reportPath = (dir / "report.txt").string();
    CHECK_THROWS_WITH(compareParts(bad), Catch::Contains(".json"));
    CHECK_FALSE(fs::exists(dir / "report.txt"));
    fs::remove_all(dir);
}

TEST_CASE("compare: a design with a triangle missing is measured, with a warning", "[compare][deviation][job][degenerate]") {
    const fs::path dir = scratch("open");
    writeStl((dir / "sphere.stl").string(), sphere(kRadius, 3));
    Mesh open = cube(kHalf);
    open.triangles.pop_back();
    std::ofstream(dir / "open.stl") << asciiStl(open);
    CompareOptions o;
    o.machinedPath = (dir / "sphere.stl").string();
    o.designPath = (dir / "open.stl").string();
    o.reportPath = (dir / "report.json").string();
    const CompareReport r = compareParts(o);
    CHECK(r.machinedClosed);
    CHECK_FALSE(r.designClosed);
    REQUIRE(r.warnings.size() == 1);
    // The missing triangle leaves its three edges on one triangle each.
    CHECK_THAT(r.warnings[0], Catch::Contains("open.stl': the design is not closed (3 edges on one triangle)"));
    const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "report.json"));
    CHECK(j["design"]["closed"] == false);
    CHECK(j["warnings"].size() == 1);
    fs::remove_all(dir);
}

TEST_CASE("picture: the legend's colours and the vertex colours reach the image", "[compare][deviation][io]") {
    const Mesh machined = sphere(kRadius, 3);
    const Deviation d = measureDeviation(machined, MeshDistance(cube(kHalf)), {0.01, 0.05});
    const DeviationScale scale = deviationScale(d);
    const std::vector<Rgb> colours = deviationColours(d.distance, scale);
    const PictureLegend legend = deviationLegend(scale);
    PictureOptions po;
    po.width = 600;
    po.height = 450;
    po.vertexColours = &colours;
    po.legend = &legend;
    const Image img = renderPicture(machined, po);
    // The bar's colours appear as they are, in the right fifth of the picture.
    auto count = [&](const Rgb& c, int x0) {
        std::size_t n = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = x0; x < img.width; ++x)
                if (std::equal(c.begin(), c.end(), img.pixel(x, y))) ++n;
        return n;
    };
    CHECK(count(legend.bar.front(), img.width * 4 / 5) > 0);
    CHECK(count(legend.bar[legend.bar.size() / 2], img.width * 4 / 5) > 0);
    CHECK(count(legend.bar.back(), img.width * 4 / 5) > 0);
    // The part is shaded in its colours: blue-dominated pixels where it bulges out, red where it
    // lies inside.
    std::size_t blue = 0, red = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width * 3 / 4; ++x) {
            const std::uint8_t* p = img.pixel(x, y);
            blue += p[2] > p[0] + 40;
            red += p[0] > p[2] + 40;
        }
    CHECK(blue > 1000);
    CHECK(red > 1000);
    // Colours for another vertex count are refused.
    const std::vector<Rgb> few(3);
    po.vertexColours = &few;
    CHECK_THROWS_AS(renderPicture(machined, po), Error);
}

TEST_CASE("compare: a level set (.vdb) as the machined part and as the design", "[compare][deviation][job]") {
    const fs::path dir = scratch("vdb");
    // A block that nothing cuts, written as a level set at h = 0.5 mm.
    SimulateOptions o;
    o.inputs = {"none.ngc"};
    o.files = [](const std::string& path) -> std::optional<std::string> {
        if (path == "none.ngc") return std::string("G21 G90\nG0 X0 Y0 Z50\nM30\n");
        return std::nullopt;
    };
    o.stockBox = Box{Vec3(-kHalf), Vec3(kHalf)};
    o.defaultTool = flatEndMill(6.0, {20.0, 40.0});
    o.resolution = 0.5;
    o.vdbPath = (dir / "block.vdb").string();
    o.threads = 2;
    simulate(o);
    std::ofstream(dir / "cube.stl") << asciiStl(cube(kHalf));

    // As the design: its mesh is closed and lies on the block's faces, rounded at edges and
    // corners by less than a spacing.
    const Mesh design = readDesign(o.vdbPath);
    CHECK(checkMesh(design).closedManifold());
    CHECK(MeshDistance(design).orientation() == 1);
    const Deviation d = measureDeviation(cube(kHalf), MeshDistance(design), {0.01, 0.05});
    CHECK(d.farthest <= 0.5);
    CHECK(d.deepest >= -0.5);

    // As the machined part, against the STL block: the faces' middles lie on it.
    CompareOptions c;
    c.machinedPath = o.vdbPath;
    c.designPath = (dir / "cube.stl").string();
    const CompareReport r = compareParts(c);
    CHECK(r.machinedClosed);
    CHECK(r.deviation.farthest <= 0.5);
    CHECK(r.deviation.deepest >= -0.5);
    CHECK(r.deviation.withinArea > 0.5 * r.deviation.area);
    fs::remove_all(dir);
}

TEST_CASE("deviation: a fine design, where vertices search the hierarchy", "[compare][deviation]") {
    // A design of 8,192 triangles (a sphere of radius 5) offers every cell of these coarse spheres
    // more triangles than a cell may try, so each vertex searches the hierarchy. The design lies
    // inside the ball of radius 5 and holds the ball of radius 5 - sag: a vertex at radius 6 is
    // 1 to 1 + sag outside it, one at radius 4 is 1 - sag to 1 inside.
    const Mesh fine = sphere(5.0, 5);
    double sag = 0.0;  // 5 less the nearest face plane's distance from the centre
    for (const auto& t : fine.triangles) {
        const Vec3 n = glm::normalize(glm::cross(fine.vertices[t[1]] - fine.vertices[t[0]], fine.vertices[t[2]] - fine.vertices[t[0]]));
        sag = std::max(sag, 5.0 - glm::dot(n, fine.vertices[t[0]]));
    }
    REQUIRE(sag < 0.01);
    const MeshDistance design(fine);
    for (const double r : {6.0, 4.0}) {
        const Mesh machined = sphere(r, 3);
        const Deviation d = measureDeviation(machined, design, {0.01, 0.05});
        for (std::size_t i = 0; i < machined.vertices.size(); ++i) {
            INFO("radius " << r << ", vertex " << i);
            if (r > 5.0) CHECK((d.distance[i] >= 1.0 - 1e-12 && d.distance[i] <= 1.0 + sag));
            else CHECK((d.distance[i] <= -1.0 + sag && d.distance[i] >= -1.0 - 1e-12));
        }
    }
    // The design against itself: every vertex on it.
    const Deviation same = measureDeviation(fine, design, {0.01, 0.05});
    for (double v : same.distance) CHECK(std::abs(v) <= 1e-6);
}

TEST_CASE("deviation: what it refuses, an empty mesh, a tolerance below a micrometre", "[compare][deviation][degenerate]") {
    const MeshDistance design{cube(kHalf)};
    CHECK_THROWS_WITH(measureDeviation(sphere(kRadius, 1), MeshDistance(Mesh{}), {0.01, 0.05}), Catch::Contains("no triangles"));
    CHECK_THROWS_WITH(measureDeviation(sphere(kRadius, 1), design, {-0.01, 0.05}), Catch::Contains("tolerances"));
    CHECK_THROWS_WITH(measureDeviation(sphere(kRadius, 1), design, {0.01, std::nan("")}), Catch::Contains("tolerances"));
    Mesh bad = sphere(kRadius, 1);
    bad.vertices[3].y = std::numeric_limits<double>::infinity();
    CHECK_THROWS_WITH(measureDeviation(bad, design, {0.01, 0.05}), Catch::Contains("finite"));
    const Deviation none = measureDeviation(Mesh{}, design, {0.01, 0.05});
    REQUIRE(none.histogram.size() == 1);
    CHECK(none.histogram[0].points == 0);
    // 1e-300 mm steps like 0: 1, 2, 5 ... um, a few dozen bins, not hundreds.
    const Deviation tiny = measureDeviation(sphere(kRadius, 2), design, {1e-300, 1e-300});
    CHECK(tiny.histogram.size() < 30);
    CHECK(tiny.histogram.back().hi == Approx(1.0));
}
