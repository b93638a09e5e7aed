#include "dexelmill/stock/fine_features.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include <tbb/parallel_for.h>

#include "dexelmill/geometry/cell_regions.h"

namespace dexelmill {

namespace {

/// Whether a lattice point of a dexel with n points at (i + 1/2) h lies in [lo, hi]: strictly
/// inside when `open` (a point on a segment's end is not in its material), ends included when
/// not. The points are the floats TriDexelStock::inside compares with. The first point at or
/// above lo is the one to test, or the next where that one is lo itself and the stretch open
/// (later ones lie beyond); the one below is tested too, in case rounding to float moved a point
/// across lo.
bool holdsPoint(float lo, float hi, double h, int n, bool open) {
    const int first = int(std::ceil(double(lo) / h - 0.5));
    for (int i = std::max(0, first - 1); i <= first + 1 && i < n; ++i) {
        const float v = float((i + 0.5) * h);
        if (open ? (lo < v && v < hi) : (lo <= v && v <= hi)) return true;
    }
    return false;
}

/// The stretches grouped into regions (FineStretches::regionCount), the regions summed up.
FineStretches summarise(const TriDexelStock& stock, const std::vector<FineStretch>& stretches) {
    FineStretches out;
    out.count = stretches.size();
    if (stretches.empty()) return out;
    const Lattice& lat = stock.lattice();
    const double h = lat.h, cellSize = kFineRegionJoin * h;
    std::array<std::int64_t, 3> dims{};
    for (int a = 0; a < 3; ++a)
        dims[std::size_t(a)] = std::int64_t(std::ceil(lat.n[std::size_t(a)] * h / cellSize)) + 1;
    const auto middleOf = [&](const FineStretch& s) {
        return stock.dexelLine(axisFromIndex(s.family), s.ib, s.ic)
            .at(0.5 * (double(s.lo) + double(s.hi)));
    };
    const auto cellOf = [&](const Vec3& p) {
        std::array<std::int64_t, 3> c{};
        for (int a = 0; a < 3; ++a)
            c[std::size_t(a)] =
                std::clamp(std::int64_t(std::floor((p[a] - lat.origin[a]) / cellSize)),
                           std::int64_t(0), dims[std::size_t(a)] - 1);
        return std::size_t(c[0] + dims[0] * (c[1] + dims[1] * c[2]));
    };

    // The cells the stretches' middles lie in, joined where they touch.
    std::vector<std::size_t> cellOfStretch(stretches.size());
    for (std::size_t i = 0; i < stretches.size(); ++i)
        cellOfStretch[i] = cellOf(middleOf(stretches[i]));
    const std::vector<std::uint32_t> regionOf = touchingRegions(dims, cellOfStretch);

    // The regions, numbered as their first stretch comes, with their lengths per family.
    std::vector<FineRegion> regions(*std::max_element(regionOf.begin(), regionOf.end()) +
                                    std::size_t(1));
    std::vector<std::array<double, 3>> lengths(regions.size(), {0.0, 0.0, 0.0});
    for (std::size_t i = 0; i < stretches.size(); ++i) {
        const FineStretch& s = stretches[i];
        const std::size_t r = regionOf[i];
        FineRegion& region = regions[r];
        const double length = double(s.hi) - double(s.lo);
        lengths[r][std::size_t(s.family)] += length;
        ++region.stretches;
        const Line line = stock.dexelLine(axisFromIndex(s.family), s.ib, s.ic);
        Vec3 lo = line.at(s.lo), hi = line.at(s.hi);
        for (int a = 0; a < 3; ++a)
            if (a != s.family) lo[a] -= 0.5 * h, hi[a] += 0.5 * h;
        region.box.expand(lo);
        region.box.expand(hi);
        if (length > region.widestMm) region.widestMm = length, region.widestAt = middleOf(s);
    }
    for (std::size_t r = 0; r < regions.size(); ++r) {
        FineRegion& region = regions[r];
        region.volumeMm3 = h * h * *std::max_element(lengths[r].begin(), lengths[r].end());
        out.volumeMm3 += region.volumeMm3;
        if (region.widestMm > out.widestMm)
            out.widestMm = region.widestMm, out.widestAt = region.widestAt;
    }
    out.regionCount = regions.size();
    std::stable_sort(regions.begin(), regions.end(), [](const FineRegion& x, const FineRegion& y) {
        return x.volumeMm3 > y.volumeMm3;
    });
    if (regions.size() > kFineRegionsKept) regions.resize(kFineRegionsKept);
    out.regions = std::move(regions);
    return out;
}

}  // namespace

void findFineStretches(const TriDexelStock& stock, std::vector<FineStretch>& material,
                       std::vector<FineStretch>& gaps) {
    const double h = stock.lattice().h;
    for (int a = 0; a < 3; ++a) {
        if (!stock.has(axisFromIndex(a))) continue;
        const DexelFamily& fam = stock.family(axisFromIndex(a));
        const int n = stock.lattice().n[std::size_t(a)];
        std::vector<std::vector<FineStretch>> rowMaterial(std::size_t(fam.nc())),
            rowGaps(std::size_t(fam.nc()));
        tbb::parallel_for(0, fam.nc(), [&](int ic) {
            for (int ib = 0; ib < fam.nb(); ++ib) {
                const SegmentSpan segs = fam.segments(ib, ic);
                for (std::size_t k = 0; k < segs.size; ++k) {
                    const Segment& s = segs[k];
                    if (!holdsPoint(s.lo, s.hi, h, n, true))
                        rowMaterial[std::size_t(ic)].push_back({a, ib, ic, s.lo, s.hi});
                    if (k + 1 < segs.size && segs[k + 1].lo > s.hi &&
                        !holdsPoint(s.hi, segs[k + 1].lo, h, n, false))
                        rowGaps[std::size_t(ic)].push_back({a, ib, ic, s.hi, segs[k + 1].lo});
                }
            }
        });
        for (const auto& row : rowMaterial) material.insert(material.end(), row.begin(), row.end());
        for (const auto& row : rowGaps) gaps.insert(gaps.end(), row.begin(), row.end());
    }
}

FineFeatures finerThanLattice(const TriDexelStock& stock) {
    std::vector<FineStretch> material, gaps;
    findFineStretches(stock, material, gaps);
    FineFeatures out;
    out.material = summarise(stock, material);
    out.gaps = summarise(stock, gaps);
    return out;
}

}  // namespace dexelmill
