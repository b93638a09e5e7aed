// Excess after the cut: the stock outside the design, its thickness and its regions.
#include "dexelmill/compare/excess.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <unordered_map>

#include <tbb/parallel_for.h>

#include "compare/detail/deepest.h"
#include "dexelmill/error.h"

namespace dexelmill {

namespace {

/// Regions are joined on a grid of cells this many spacings wide, and at least this fraction of
/// the stock's longest side (so that a large stock has at most about 64^3 cells).
constexpr double kCellSpacings = 4.0;
constexpr double kCellsAlongLongest = 64.0;

/// A piece of excess on one dexel, and whether a design segment ends at each of its ends.
struct Piece {
    DexelStretch line;
    bool designLo = false, designHi = false;
};

/// The stock's segments minus the design's on one dexel.
void difference(const SegmentSpan& stock, const SegmentSpan& design, DexelStretch at, std::vector<Piece>& out) {
    std::size_t k = 0;
    for (const Segment& s : stock) {
        double lo = s.lo;
        bool fromDesign = false;
        while (k < design.size && design[k].hi <= lo) ++k;
        for (std::size_t j = k; j < design.size && double(design[j].lo) < double(s.hi); ++j) {
            const double dlo = design[j].lo, dhi = design[j].hi;
            if (dlo > lo) {
                at.lo = lo, at.hi = dlo;
                out.push_back({at, fromDesign, true});
            }
            lo = std::max(lo, dhi);
            fromDesign = true;
        }
        if (double(s.hi) > lo) {
            at.lo = lo, at.hi = s.hi;
            out.push_back({at, fromDesign, false});
        }
    }
}

/// The largest distance along the dexel from a point of the piece to a design end that bounds
/// it: the distance to the surface is at most this. Infinite when no design segment bounds it.
double alongBound(const Piece& p) {
    const double len = p.line.hi - p.line.lo;
    if (p.designLo && p.designHi) return 0.5 * len;
    if (p.designLo || p.designHi) return len;
    return std::numeric_limits<double>::infinity();
}

}  // namespace

Excess findExcess(const DesignPart& design, const TriDexelStock& stock, double tolerance, std::size_t maxRegions) {
    const Lattice& lattice = stock.lattice();
    const Lattice& dl = design.dexels.lattice();
    if (dl.n != lattice.n || dl.h != lattice.h || dl.origin != lattice.origin)
        throw Error("excess: the design is not cast on the stock's lattice");
    const Axis measure = stock.measuringFamily();
    const Vec3 extent = Vec3(lattice.n[0], lattice.n[1], lattice.n[2]) * lattice.h;
    const double cell = std::max(kCellSpacings * lattice.h, std::max({extent.x, extent.y, extent.z}) / kCellsAlongLongest);
    const std::array<std::int64_t, 3> cells{std::int64_t(std::ceil(extent.x / cell)) + 1,
                                            std::int64_t(std::ceil(extent.y / cell)) + 1,
                                            std::int64_t(std::ceil(extent.z / cell)) + 1};
    auto cellOf = [&](int a, double along, int b, double atB, int c, double atC) {
        std::array<std::int64_t, 3> i{};
        i[std::size_t(a)] = std::int64_t(along / cell);
        i[std::size_t(b)] = std::int64_t(atB / cell);
        i[std::size_t(c)] = std::int64_t(atC / cell);
        return i[0] + cells[0] * (i[1] + cells[1] * i[2]);
    };

    Excess result;
    // The pieces to search, and the measuring family's volume per cell.
    std::vector<Piece> search;
    std::unordered_map<std::int64_t, double> cellVolume;
    for (int a = 0; a < 3; ++a) {
        const Axis ax = axisFromIndex(a);
        if (!stock.has(ax) || !design.dexels.has(ax)) continue;
        const DexelFamily& sf = stock.family(ax);
        const DexelFamily& df = design.dexels.family(ax);
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        std::vector<Piece> pieces;
        for (int ic = 0; ic < sf.nc(); ++ic)
            for (int ib = 0; ib < sf.nb(); ++ib) {
                pieces.clear();
                difference(sf.segments(ib, ic), df.segments(ib, ic), DexelStretch{ax, ib, ic, 0.0, 0.0}, pieces);
                const double atB = (ib + 0.5) * lattice.h, atC = (ic + 0.5) * lattice.h;
                for (const Piece& p : pieces) {
                    if (ax == measure) {
                        // The piece's length, split at the cells' walls.
                        for (double lo = p.line.lo; lo < p.line.hi;) {
                            const double wall = (std::floor(lo / cell) + 1.0) * cell;
                            const double hi = std::min(p.line.hi, wall);
                            cellVolume[cellOf(a, 0.5 * (lo + hi), b, atB, c, atC)] += (hi - lo) * lattice.h * lattice.h;
                            lo = hi;
                        }
                    }
                    if (alongBound(p) > tolerance) {
                        search.push_back(p);
                        search.back().line.bound = alongBound(p);
                    }
                }
            }
    }
    for (const auto& [k, v] : cellVolume) result.volume += v;

    // Join the searched pieces' cells into regions (cells that share a face, an edge or a corner).
    std::unordered_map<std::int64_t, std::size_t> id;
    std::vector<std::size_t> parent;
    auto find = [&](std::size_t i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    // A piece's cells follow one another, so they join; its first names its region.
    std::vector<std::int64_t> firstCell(search.size());
    for (std::size_t i = 0; i < search.size(); ++i) {
        const DexelStretch& s = search[i].line;
        const int a = index(s.family), b = (a + 1) % 3, c = (a + 2) % 3;
        const double atB = (s.ib + 0.5) * lattice.h, atC = (s.ic + 0.5) * lattice.h;
        firstCell[i] = cellOf(a, s.lo, b, atB, c, atC);
        for (double t = std::floor(s.lo / cell) * cell; t < s.hi; t += cell) {
            const std::int64_t k = cellOf(a, std::clamp(t + 0.5 * cell, s.lo, s.hi), b, atB, c, atC);
            if (id.emplace(k, parent.size()).second) parent.push_back(parent.size());
        }
    }
    for (const auto& [k, i] : id) {
        const std::int64_t x = k % cells[0], y = (k / cells[0]) % cells[1], z = k / (cells[0] * cells[1]);
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const std::int64_t nx = x + dx, ny = y + dy, nz = z + dz;
                    if (nx < 0 || ny < 0 || nz < 0 || nx >= cells[0] || ny >= cells[1] || nz >= cells[2]) continue;
                    const auto it = id.find(nx + cells[0] * (ny + cells[1] * nz));
                    if (it != id.end()) parent[find(it->second)] = find(i);
                }
    }
    // Each region's pieces, and its thickness.
    std::unordered_map<std::size_t, std::size_t> regionOf;
    std::vector<std::vector<DexelStretch>> regionLines;
    std::vector<std::vector<std::int64_t>> regionCells;
    for (std::size_t i = 0; i < search.size(); ++i) {
        const std::size_t root = find(id.at(firstCell[i]));
        const auto [it, fresh] = regionOf.emplace(root, regionLines.size());
        if (fresh) regionLines.emplace_back(), regionCells.emplace_back();
        regionLines[it->second].push_back(search[i].line);
    }
    for (const auto& [k, i] : id) {
        const auto it = regionOf.find(find(i));
        if (it != regionOf.end()) regionCells[it->second].push_back(k);
    }
    const double eps = depthBound(tolerance, lattice.h);
    std::vector<Deepest> thickest(regionLines.size());
    tbb::parallel_for(std::size_t(0), regionLines.size(), [&](std::size_t r) {
        thickest[r] = deepestPoint(*design.distance, lattice, regionLines[r], eps);
    });
    for (std::size_t r = 0; r < regionLines.size(); ++r) {
        if (!(thickest[r].depth > tolerance)) continue;
        ExcessRegion region;
        region.thickness = thickest[r].depth;
        region.point = thickest[r].point;
        std::sort(regionCells[r].begin(), regionCells[r].end());
        for (const std::int64_t k : regionCells[r]) {
            const Vec3 lo = lattice.origin + Vec3(double(k % cells[0]), double((k / cells[0]) % cells[1]),
                                                  double(k / (cells[0] * cells[1]))) * cell;
            region.box.expand(lo);
            region.box.expand(lo + Vec3(cell));
            const auto v = cellVolume.find(k);
            if (v != cellVolume.end()) region.volume += v->second;
        }
        region.box = Box{glm::max(region.box.lo, lattice.origin), glm::min(region.box.hi, lattice.origin + extent)};
        if (region.thickness > result.thickness) result.thickness = region.thickness, result.point = region.point;
        result.regions.push_back(region);
    }
    std::sort(result.regions.begin(), result.regions.end(), [](const ExcessRegion& x, const ExcessRegion& y) {
        return x.volume != y.volume ? x.volume > y.volume : x.thickness > y.thickness;
    });
    if (result.regions.size() > maxRegions) result.regions.resize(maxRegions);
    return result;
}

}  // namespace dexelmill
