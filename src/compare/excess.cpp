// Excess after the cut: the stock outside the design, its thickness and its regions.
#include "dexelmill/compare/excess.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

#include "compare/detail/deepest.h"
#include "dexelmill/error.h"
#include "dexelmill/geometry/cell_regions.h"
#include "memory/pages.h"

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
    const std::size_t cellCount = std::size_t(cells[0] * cells[1] * cells[2]);
    const std::array<std::size_t, 3> stride{1, std::size_t(cells[0]), std::size_t(cells[0] * cells[1])};
    // The cell along axis a of a coordinate. Stock lies inside the lattice's box, so the clamp
    // only guards the arrays.
    auto step = [&](int a, double along) {
        return std::size_t(std::clamp<std::int64_t>(std::int64_t(along / cell), 0, cells[std::size_t(a)] - 1));
    };
    auto cellOf = [&](int a, double along, int b, double atB, int c, double atC) {
        return step(a, along) * stride[std::size_t(a)] + step(b, atB) * stride[std::size_t(b)] +
               step(c, atC) * stride[std::size_t(c)];
    };

    // The design's segment ends are surface points to a float's rounding.
    const double rounding = endRounding(lattice);
    Excess result;
    // The pieces to search, and the measuring family's volume per cell. Each row of dexels (one
    // ic of a family) is differenced on its own thread, twice: first to sum its volume per cell
    // (in dexel order, in a dense array over the row's cells) and count its pieces to search,
    // then to write those pieces at the row's place in one array. Rows are gathered in order, so
    // the sums and the order of the pieces do not depend on the threads, and no list grows piece
    // by piece.
    std::vector<DexelStretch> search;
    std::vector<double> cellVolume(cellCount, 0.0);
    for (int a = 0; a < 3; ++a) {
        const Axis ax = axisFromIndex(a);
        if (!stock.has(ax) || !design.dexels.has(ax)) continue;
        const DexelFamily& sf = stock.family(ax);
        const DexelFamily& df = design.dexels.family(ax);
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        const auto alongCells = std::size_t(cells[std::size_t(a)]);
        const std::size_t rowCells = alongCells * std::size_t(cells[std::size_t(b)]);
        // Each row's pieces, given to `use` with the dexel's coordinates across it.
        auto eachPiece = [&](int ic, auto&& use) {
            std::vector<Piece> pieces;
            for (int ib = 0; ib < sf.nb(); ++ib) {
                pieces.clear();
                difference(sf.segments(ib, ic), df.segments(ib, ic), DexelStretch{ax, ib, ic, 0.0, 0.0}, pieces);
                for (const Piece& p : pieces) use(p, (ib + 0.5) * lattice.h, (ic + 0.5) * lattice.h);
            }
        };
        struct Row {
            std::size_t searched = 0;
            std::vector<std::pair<std::size_t, double>> volume;  ///< (cell, mm^3), by cell
        };
        std::vector<Row> rows(std::size_t(sf.nc()));
        tbb::parallel_for(0, sf.nc(), [&](int ic) {
            Row& row = rows[std::size_t(ic)];
            std::vector<double> sum;  // by (along, across), made at the row's first piece
            eachPiece(ic, [&](const Piece& p, double atB, double) {
                if (ax == measure) {
                    if (sum.empty()) sum.assign(rowCells, 0.0);
                    // The piece's length, split at the cells' walls.
                    for (double lo = p.line.lo; lo < p.line.hi;) {
                        const double wall = (std::floor(lo / cell) + 1.0) * cell;
                        const double hi = std::min(p.line.hi, wall);
                        sum[step(a, 0.5 * (lo + hi)) + alongCells * step(b, atB)] +=
                            (hi - lo) * lattice.dexelShare(ax, p.line.ib, p.line.ic) * lattice.h * lattice.h;
                        lo = hi;
                    }
                }
                row.searched += alongBound(p) > tolerance;
            });
            if (sum.empty()) return;
            const std::size_t across = step(c, (ic + 0.5) * lattice.h) * stride[std::size_t(c)];
            for (std::size_t i = 0; i < rowCells; ++i)
                if (sum[i] > 0.0)
                    row.volume.emplace_back((i % alongCells) * stride[std::size_t(a)] +
                                                (i / alongCells) * stride[std::size_t(b)] + across,
                                            sum[i]);
        });
        std::vector<std::size_t> at(rows.size() + 1, search.size());
        for (std::size_t r = 0; r < rows.size(); ++r) {
            for (const auto& [k, v] : rows[r].volume) cellVolume[k] += v;
            at[r + 1] = at[r] + rows[r].searched;
        }
        detail::reservePopulated(search, at.back());
        search.resize(at.back());
        tbb::parallel_for(0, sf.nc(), [&](int ic) {
            std::size_t next = at[std::size_t(ic)];
            eachPiece(ic, [&](const Piece& p, double, double) {
                const double bound = alongBound(p);
                if (!(bound > tolerance)) return;
                search[next] = p.line;
                search[next++].bound = bound + rounding;
            });
        });
    }
    for (const double v : cellVolume) result.volume += v;

    // Join the searched pieces' cells into regions (cells that share a face, an edge or a corner).
    constexpr std::uint32_t kNone = ~0u;
    std::vector<std::uint32_t> idOf(cellCount, kNone);  // each searched cell's number
    std::vector<std::size_t> idCell;                     // each number's cell
    // A piece's cells follow one another, so they join; its first names its region.
    std::vector<std::size_t> firstCell(search.size());
    for (std::size_t i = 0; i < search.size(); ++i) {
        const DexelStretch& s = search[i];
        const int a = index(s.family), b = (a + 1) % 3, c = (a + 2) % 3;
        const double atB = (s.ib + 0.5) * lattice.h, atC = (s.ic + 0.5) * lattice.h;
        firstCell[i] = cellOf(a, s.lo, b, atB, c, atC);
        for (double t = std::floor(s.lo / cell) * cell; t < s.hi; t += cell) {
            const std::size_t k = cellOf(a, std::clamp(t + 0.5 * cell, s.lo, s.hi), b, atB, c, atC);
            if (idOf[k] == kNone) {
                idOf[k] = std::uint32_t(idCell.size());
                idCell.push_back(k);
            }
        }
    }
    const std::vector<std::uint32_t> label = touchingRegions(cells, idCell);  // by number
    // Each region's pieces, gathered region by region (in their order within a region), and its
    // cells.
    std::vector<std::uint32_t> regionOf(idCell.size(), kNone);  // by label
    std::vector<std::uint32_t> pieceRegion(search.size());
    std::vector<std::size_t> regionStart{0};
    for (std::size_t i = 0; i < search.size(); ++i) {
        std::uint32_t& r = regionOf[label[idOf[firstCell[i]]]];
        if (r == kNone) {
            r = std::uint32_t(regionStart.size() - 1);
            regionStart.push_back(0);
        }
        pieceRegion[i] = r;
        ++regionStart[r + 1];
    }
    const std::size_t regions = regionStart.size() - 1;
    std::partial_sum(regionStart.begin(), regionStart.end(), regionStart.begin());
    // One region (a common case) is already in place.
    if (regions > 1) {
        std::vector<DexelStretch> grouped;
        detail::reservePopulated(grouped, search.size());
        grouped.resize(search.size());
        std::vector<std::size_t> next(regionStart.begin(), regionStart.end() - 1);
        for (std::size_t i = 0; i < search.size(); ++i) grouped[next[pieceRegion[i]]++] = search[i];
        search.swap(grouped);
    }
    std::vector<std::vector<std::size_t>> regionCells(regions);
    for (std::uint32_t i = 0; i < idCell.size(); ++i) {
        const std::uint32_t r = regionOf[label[i]];
        if (r != kNone) regionCells[r].push_back(idCell[i]);
    }
    const double eps = depthBound(tolerance, lattice.h);
    const std::vector<Deepest> thickest = deepestPoints(design, lattice, search, regionStart, eps);
    for (std::size_t r = 0; r < regions; ++r) {
        if (!(thickest[r].depth > tolerance)) continue;
        ExcessRegion region;
        region.thickness = thickest[r].depth;
        region.point = thickest[r].point;
        std::sort(regionCells[r].begin(), regionCells[r].end());
        for (const std::size_t cellIndex : regionCells[r]) {
            const auto k = std::int64_t(cellIndex);
            const Vec3 lo = lattice.origin + Vec3(double(k % cells[0]), double((k / cells[0]) % cells[1]),
                                                  double(k / (cells[0] * cells[1]))) * cell;
            region.box.expand(lo);
            region.box.expand(lo + Vec3(cell));
            region.volume += cellVolume[cellIndex];
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
