// The machined surface against the design: signed distances per vertex and at points inside the
// triangles, their statistics and the colours that show them.
#include "dexelmill/compare/deviation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "compare/detail/surface_samples.h"
#include "dexelmill/decimal.h"
#include "dexelmill/error.h"
#include "dexelmill/span.h"

namespace dexelmill {

namespace {

/// A vertex this close to a design triangle (mm) is on the design's surface: where vertices search
/// the hierarchy (a fine design), its distance is taken as that, unsigned, at most this much from
/// the exact signed distance. It is a sixtieth of the rounding of an STL's single-precision
/// coordinates at 1 m, and spares the search for machined faces that lie on design faces.
constexpr double kOnSurface = 1e-6;

/// The cells vertices are measured in: about this many of the mesh's mean edge lengths wide (so
/// about 64 vertices to a flat cell), at most kCellsPerAxis along each axis; and the most design
/// triangles a cell may offer its vertices before they search the hierarchy instead. On basemach
/// (1.2 million vertices, a 1,564-triangle design, one thread) 92 % of the vertices then try 5.5
/// triangles on average, and measureDeviation takes 0.69 s, against 0.89 s with every vertex
/// searching the hierarchy from its predecessor's nearest triangle; 4 edges or 64 triangles
/// measured slower.
constexpr double kCellEdges = 8.0;
constexpr std::uint64_t kCellsPerAxis = std::uint64_t(1) << 21;
constexpr std::size_t kMaxCandidates = 16;
constexpr std::size_t kEdgeSample = 4096;
/// The sampling inside the triangles (compare/detail/surface_samples.h): its spacing is never finer
/// than this fraction of the part's longest side; it is the finest whose points inside the
/// triangles number at most the mesh's vertices or kMinSampleBudget, whichever is more, so that a
/// fine mesh costs at most twice its vertices' measure and a coarse one about kMinSampleBudget
/// points (a few hundredths of a second). On an uncut 12-triangle block of 50 x 50 x 20 mm the
/// budget gives a spacing of about 0.6 mm; on a simulated mesh (hood.ngc at h = 2 mm, 2.3 million
/// vertices) it rises above every edge, and only the vertices are measured.
constexpr double kFinestSpacing = 1e-4;
constexpr std::uint64_t kMinSampleBudget = std::uint64_t(1) << 16;
/// A distance within this fraction of the part's scale (the larger of its longest side and its
/// largest coordinate, the size the rounding of its coordinates follows) is rounding, and is taken
/// as 0. A point lying on a design face gets a distance of a few units in the last place of its
/// coordinates (1.1e-14 mm on a 40 mm block, where that unit is 7e-15 mm); this is about 4,500
/// such units (2^-52 = 2.2e-16 of the scale), and 60,000 times below the rounding of an STL's
/// single-precision coordinates (6e-8 of the scale), the least deviation a mesh file can carry.
constexpr double kRounding = 1e-12;
/// Rounding of the cell a vertex falls in may put it this fraction of the cell's size outside it;
/// the cell's reach covers that.
constexpr double kCellMargin = 1e-9;

/// 1, 2, 5, 10, 20, 50, ...
double ladder(int k) {
    static const double mantissa[3] = {1.0, 2.0, 5.0};
    return mantissa[k % 3] * std::pow(10.0, k / 3);
}

/// The histogram's steps when a tolerance is below it (mm): the tolerance, then 1, 2, 5, ... um.
constexpr double kHistogramUnit = 0.001;

/// The k-th edge of the histogram beyond a tolerance (as a distance from the design): the
/// tolerance, then 2, 5, 10, 20, ... times it (or 1, 2, 5, ... um for a tolerance below 1 um).
double edge(int k, double tolerance) {
    if (k == 0) return tolerance;
    return tolerance >= kHistogramUnit ? tolerance * ladder(k) : kHistogramUnit * ladder(k - 1);
}

/// The scale's colours (sRGB).
constexpr Rgb kWithin{70, 170, 90};
constexpr Rgb kGougeLight{250, 175, 155}, kGougeDark{165, 0, 30};
constexpr Rgb kExcessLight{165, 200, 250}, kExcessDark{25, 50, 160};

Rgb mix(const Rgb& a, const Rgb& b, double t) {
    t = std::clamp(t, 0.0, 1.0);
    Rgb c;
    for (int k = 0; k < 3; ++k) c[std::size_t(k)] = std::uint8_t(std::lround(a[std::size_t(k)] + t * (b[std::size_t(k)] - a[std::size_t(k)])));
    return c;
}

/// Colours per third of the legend's bar.
constexpr int kBarSteps = 64;

}  // namespace

namespace {

/// The signed distance of every point to the design, measured cell by cell on a grid of cubes
/// `cell` wide. One search per cell, from its centre c with the cube's half-diagonal r, finds the
/// triangles within distance(c) + 2 r of c: every point of the cube has its nearest among them (it
/// is at most distance(c) + r from its nearest, which is then at most distance(c) + 2 r from c).
/// When there are few, every point of the cell tries just those. Otherwise (a fine design) each
/// point searches the hierarchy, starting from the previous point's nearest triangle, and a point
/// within kOnSurface of that triangle takes that distance (unsigned): the exact one is between 0
/// and it.
std::vector<double> signedDistances(Span<Vec3> points, double cell, const MeshDistance& design) {
    const std::size_t n = points.size;
    std::vector<double> distance(n);
    if (n == 0) return distance;
    Box box;
    for (const Vec3& p : points) box.expand(p);
    const double longest = std::max({box.size().x, box.size().y, box.size().z});
    cell = std::max({cell, longest / double(kCellsPerAxis - 1), std::numeric_limits<double>::min()});
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
        const Vec3 u = glm::floor((points[i] - box.lo) / cell);
        keyed[i] = {std::uint64_t(u.x) | std::uint64_t(u.y) << 21 | std::uint64_t(u.z) << 42, std::uint32_t(i)};
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    std::vector<std::size_t> groups;
    for (std::size_t i = 0; i < n; ++i)
        if (i == 0 || keyed[i].first != keyed[i - 1].first) groups.push_back(i);
    groups.push_back(n);
    const double halfDiagonal = 0.5 * std::sqrt(3.0) * cell * (1.0 + kCellMargin);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups.size() - 1), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<std::uint32_t> slots;
        for (std::size_t g = r.begin(); g != r.end(); ++g) {
            const std::uint64_t key = keyed[groups[g]].first;
            const Vec3 corner(double(key & 0x1fffff), double(key >> 21 & 0x1fffff), double(key >> 42));
            const Vec3 c = box.lo + (corner + Vec3(0.5)) * cell;
            const double reach = design.distance(c) + 2.0 * halfDiagonal;
            if (design.slotsNear(c, reach, kMaxCandidates, slots)) {
                for (std::size_t k = groups[g]; k < groups[g + 1]; ++k) {
                    const std::uint32_t v = keyed[k].second;
                    distance[v] = design.signedDistanceAmong(points[v], slots);
                }
                continue;
            }
            std::uint32_t hint = 0;
            for (std::size_t k = groups[g]; k < groups[g + 1]; ++k) {
                const Vec3& p = points[keyed[k].second];
                const double near = design.distanceTo(p, hint);
                distance[keyed[k].second] = near <= kOnSurface ? near : design.signedDistance(p, &hint);
            }
        }
    });
    return distance;
}

}  // namespace

Deviation measureDeviation(const Mesh& machined, const MeshDistance& design, const DeviationTolerance& tolerance) {
    for (double t : {tolerance.gouge, tolerance.excess})
        if (!(t >= 0.0) || !std::isfinite(t)) throw Error("deviation: the tolerances must be finite, 0 mm or more");
    if (design.triangleCount() == 0) throw Error("deviation: the design has no triangles");
    const std::size_t n = machined.vertices.size();
    if (n > std::numeric_limits<std::uint32_t>::max())
        throw Error("deviation: a mesh of " + std::to_string(n) + " vertices is too large to measure");
    for (const Vec3& v : machined.vertices)
        if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
            throw Error("deviation: the mesh has a vertex that is not a finite point");
    Deviation dev;
    dev.tolerance = tolerance;
    if (n == 0) {
        dev.histogram.push_back({-tolerance.gouge, tolerance.excess, 0.0, 0});
        return dev;
    }
    // The vertices, in cells about kCellEdges of the mesh's mean edge lengths wide (that mean from
    // a few thousand triangles spread over the list).
    const std::size_t nt = machined.triangles.size();
    const std::size_t stride = std::max<std::size_t>(1, nt / kEdgeSample);
    double edges = 0.0;
    std::size_t sampled = 0;
    for (std::size_t t = 0; t < nt; t += stride, ++sampled)
        for (int k = 0; k < 3; ++k)
            edges += glm::length(machined.vertices[machined.triangles[t][std::size_t(k)]] -
                                 machined.vertices[machined.triangles[t][std::size_t((k + 1) % 3)]]);
    const Box box = machined.bounds();
    const double size = std::max({box.size().x, box.size().y, box.size().z});
    dev.distance = signedDistances({machined.vertices.data(), n}, sampled == 0 ? size : kCellEdges * edges / (3.0 * double(sampled)),
                                   design);

    // The points inside the triangles: every point of the surface lies within spacing / sqrt(3) of
    // a measured point, and the distance to the design changes by at most as much as the point
    // moves, so its distance lies as near that point's.
    const SurfaceSamples samples = sampleSurface(machined, std::max(kFinestSpacing * size, std::numeric_limits<double>::min()),
                                                 std::max<std::uint64_t>(kMinSampleBudget, n));
    dev.spacing = samples.spacing;
    const std::vector<Vec3>& inner = samples.points;
    std::vector<double> innerDistance = signedDistances({inner.data(), inner.size()}, kCellEdges * dev.spacing, design);
    // A point's coordinates, an inner point's too (it lies off its triangle by a few units in their
    // last place), round: a distance as small as that is 0, and a face that lies on the design is
    // measured on it.
    const double scale = std::max({size, std::abs(box.lo.x), std::abs(box.lo.y), std::abs(box.lo.z), std::abs(box.hi.x),
                                   std::abs(box.hi.y), std::abs(box.hi.z)});
    for (std::vector<double>* distances : {&dev.distance, &innerDistance})
        for (double& d : *distances)
            if (std::abs(d) <= kRounding * scale) d = 0.0;

    // Every measured point with its distance and the area it stands for.
    const auto forEachPoint = [&](auto&& visit) {
        for (std::size_t i = 0; i < n; ++i) visit(dev.distance[i], samples.vertexArea[i], machined.vertices[i]);
        for (std::size_t i = 0; i < inner.size(); ++i) visit(innerDistance[i], samples.pointArea[i], inner[i]);
    };
    double sum2 = 0.0;
    forEachPoint([&](double d, double a, const Vec3& p) {
        dev.area += a;
        sum2 += a * d * d;
        if (d < -tolerance.gouge) dev.gougeArea += a;
        else if (d > tolerance.excess) dev.excessArea += a;
        else dev.withinArea += a;
        if (d < dev.deepest) dev.deepest = d, dev.deepestPoint = p;
        if (d > dev.farthest) dev.farthest = d, dev.farthestPoint = p;
    });
    dev.rms = dev.area > 0.0 ? std::sqrt(sum2 / dev.area) : 0.0;
    const double g = tolerance.gouge, e = tolerance.excess;
    int gougeSteps = 0, excessSteps = 0;
    while (-dev.deepest > edge(gougeSteps, g)) ++gougeSteps;
    while (dev.farthest > edge(excessSteps, e)) ++excessSteps;

    // Bins: gouge ones deepest first, the one within tolerance, excess ones nearest first.
    for (int k = gougeSteps; k >= 1; --k) dev.histogram.push_back({-edge(k, g), -edge(k - 1, g), 0.0, 0});
    const std::size_t within = dev.histogram.size();
    dev.histogram.push_back({-g, e, 0.0, 0});
    for (int k = 1; k <= excessSteps; ++k) dev.histogram.push_back({edge(k - 1, e), edge(k, e), 0.0, 0});
    forEachPoint([&](double d, double a, const Vec3&) {
        std::size_t bin = within;
        if (d < -g) {
            int k = 1;  // the bin [-edge(k), -edge(k - 1)) that holds d
            while (d < -edge(k, g)) ++k;
            bin = within - std::size_t(k);
        } else if (d > e) {
            int k = 1;  // the bin (edge(k - 1), edge(k)]
            while (d > edge(k, e)) ++k;
            bin = within + std::size_t(k);
        }
        dev.histogram[bin].area += a;
        ++dev.histogram[bin].points;
    });
    return dev;
}

DeviationScale deviationScale(const Deviation& deviation) {
    DeviationScale s;
    s.tolerance = deviation.tolerance;
    s.gougeFull = std::max(-deviation.deepest, 2.0 * deviation.tolerance.gouge);
    s.excessFull = std::max(deviation.farthest, 2.0 * deviation.tolerance.excess);
    return s;
}

Rgb deviationColour(double d, const DeviationScale& s) {
    if (d < -s.tolerance.gouge)
        return mix(kGougeLight, kGougeDark, (-d - s.tolerance.gouge) / (s.gougeFull - s.tolerance.gouge));
    if (d > s.tolerance.excess)
        return mix(kExcessLight, kExcessDark, (d - s.tolerance.excess) / (s.excessFull - s.tolerance.excess));
    return kWithin;
}

std::vector<Rgb> deviationColours(const std::vector<double>& distance, const DeviationScale& scale) {
    std::vector<Rgb> colours(distance.size());
    for (std::size_t i = 0; i < colours.size(); ++i) colours[i] = deviationColour(distance[i], scale);
    return colours;
}

PictureLegend deviationLegend(const DeviationScale& s) {
    PictureLegend legend;
    legend.title = "deviation (mm)";
    // Bottom third: from the full gouge colour up to the lightest; then green; then excess.
    for (int k = 0; k < kBarSteps; ++k)
        legend.bar.push_back(mix(kGougeDark, kGougeLight, (k + 0.5) / kBarSteps));
    for (int k = 0; k < kBarSteps; ++k) legend.bar.push_back(kWithin);
    for (int k = 0; k < kBarSteps; ++k)
        legend.bar.push_back(mix(kExcessLight, kExcessDark, (k + 0.5) / kBarSteps));
    legend.labels = {{0.0, signedLengthText(-s.gougeFull), true},
                     {1.0 / 6.0, "gouge", false},
                     {1.0 / 3.0, signedLengthText(-s.tolerance.gouge), true},
                     {0.5, "within", false},
                     {2.0 / 3.0, signedLengthText(s.tolerance.excess), true},
                     {5.0 / 6.0, "excess", false},
                     {1.0, signedLengthText(s.excessFull), true}};
    return legend;
}

}  // namespace dexelmill
