#include "dexelmill/stock/lattice.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "dexelmill/error.h"

namespace dexelmill {

namespace {

/// How close (relative to the count) a box's size over h must be to a whole number of cells to
/// be taken as one: sizes such as 20 mm at 0.1 mm, whose quotient rounds to 200.00000000000003.
constexpr double kWholeCells = 1e-9;

}  // namespace

double Lattice::share(Axis a, int i) const {
    const int ax = index(a);
    if (i < 0 || i >= n[ax] || !(coord(a, i) < stockMax[ax])) return 0.0;
    if (i + 1 < n[ax] && coord(a, i + 1) < stockMax[ax]) return 1.0;
    const double cells = (stockMax[ax] - origin[ax]) / h;
    if (std::abs(cells - n[ax]) <= kWholeCells * std::max(1.0, cells)) return 1.0;
    return cells - i;
}

Lattice Lattice::fromBox(const Box& box, double h) {
    if (!(h > 0.0) || !std::isfinite(h)) {
        std::ostringstream s;
        s << "lattice spacing must be positive, got " << h;
        throw Error(s.str());
    }
    if (box.isEmpty() || !(box.size().x > 0 && box.size().y > 0 && box.size().z > 0)) {
        throw Error("stock box must have positive size on every axis");
    }
    Lattice l;
    l.origin = box.lo;
    l.stockMax = box.hi;
    l.h = h;
    for (int a = 0; a < 3; ++a) {
        // A size that is a whole number of cells up to rounding gets exactly that many cells.
        const double cells = box.size()[a] / h;
        const double rounded = std::round(cells);
        const double n = std::abs(cells - rounded) <= kWholeCells * std::max(1.0, cells) ? rounded : std::ceil(cells);
        if (n > double(std::numeric_limits<int>::max() / 2)) {
            std::ostringstream s;
            s << "stock is " << box.size()[a] << " mm along " << "xyz"[a] << ": spacing " << h
              << " mm would need " << n << " lattice points";
            throw Error(s.str());
        }
        l.n[a] = std::max(1, int(n));
    }
    return l;
}

std::array<int, 2> Lattice::indexRange(Axis a, double lo, double hi) const {
    const int ax = index(a);
    // coord(i) = origin + (i + 1/2) h >= lo  <=>  i >= (lo - origin) / h - 1/2
    const double first = std::ceil((lo - origin[ax]) / h - 0.5);
    const double last = std::floor((hi - origin[ax]) / h - 0.5);
    // Clamped to the lattice in double before the conversion, so that a range far outside it (a
    // move to X2e8, say) or not a number at all is an empty or clipped range, never an overflow.
    if (!(first <= last)) return {0, -1};
    const double f = std::min(std::max(first, 0.0), double(n[ax]));
    const double l = std::max(std::min(last, double(n[ax] - 1)), -1.0);
    return {int(f), int(l)};
}

double endRounding(const Lattice& lattice) {
    const double longest = std::max({lattice.n[0], lattice.n[1], lattice.n[2]}) * lattice.h;
    return std::ldexp(std::max(longest, 1.0), -23);
}

}  // namespace dexelmill
