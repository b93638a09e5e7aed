#include "dexelmill/stock/fine_features.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace dexelmill {

namespace {

/// One family's stretches, and the longest's place on its dexel.
struct FamilyStretches {
    std::size_t count = 0;
    double length = 0.0;  ///< sum of lengths (mm)
    double widest = 0.0;
    int ib = 0, ic = 0;
    double middle = 0.0;  ///< the longest's middle, along the dexel (mm)

    void add(float lo, float hi, int b, int c) {
        ++count;
        const double l = double(hi) - double(lo);
        length += l;
        if (l > widest) widest = l, ib = b, ic = c, middle = 0.5 * (double(lo) + double(hi));
    }
    void join(const FamilyStretches& o) {
        count += o.count;
        length += o.length;
        if (o.widest > widest) widest = o.widest, ib = o.ib, ic = o.ic, middle = o.middle;
    }
};

struct FamilyFeatures {
    FamilyStretches material, gaps;
    void join(const FamilyFeatures& o) {
        material.join(o.material);
        gaps.join(o.gaps);
    }
};

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

FamilyFeatures familyFeatures(const TriDexelStock& stock, Axis a) {
    const DexelFamily& fam = stock.family(a);
    const double h = stock.lattice().h;
    const int n = stock.lattice().n[std::size_t(index(a))];
    return tbb::parallel_reduce(
        tbb::blocked_range<int>(0, fam.nc()), FamilyFeatures{},
        [&](const tbb::blocked_range<int>& r, FamilyFeatures f) {
            for (int ic = r.begin(); ic < r.end(); ++ic)
                for (int ib = 0; ib < fam.nb(); ++ib) {
                    const SegmentSpan segs = fam.segments(ib, ic);
                    for (std::size_t k = 0; k < segs.size; ++k) {
                        const Segment& s = segs[k];
                        if (!holdsPoint(s.lo, s.hi, h, n, true)) f.material.add(s.lo, s.hi, ib, ic);
                        if (k + 1 < segs.size && segs[k + 1].lo > s.hi &&
                            !holdsPoint(s.hi, segs[k + 1].lo, h, n, false))
                            f.gaps.add(s.hi, segs[k + 1].lo, ib, ic);
                    }
                }
            return f;
        },
        [](FamilyFeatures x, const FamilyFeatures& y) {
            x.join(y);
            return x;
        });
}

/// Folds one family's stretches into the stock's.
void addFamily(const TriDexelStock& stock, Axis a, const FamilyStretches& f, FineStretches& out) {
    const double h = stock.lattice().h;
    out.count += f.count;
    out.volumeMm3 = std::max(out.volumeMm3, h * h * f.length);
    if (f.widest > out.widestMm) {
        out.widestMm = f.widest;
        out.widestAt = stock.dexelLine(a, f.ib, f.ic).at(f.middle);
    }
}

}  // namespace

FineFeatures finerThanLattice(const TriDexelStock& stock) {
    FineFeatures out;
    for (int i = 0; i < 3; ++i) {
        const Axis a = axisFromIndex(i);
        if (!stock.has(a)) continue;
        const FamilyFeatures f = familyFeatures(stock, a);
        addFamily(stock, a, f.material, out.material);
        addFamily(stock, a, f.gaps, out.gaps);
    }
    return out;
}

}  // namespace dexelmill
