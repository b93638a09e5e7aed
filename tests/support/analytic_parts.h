/// @file analytic_parts.h
/// @brief Test support: box stocks with analytic shapes carved out dexel by dexel (no sweep
/// solver needed), and the exact surfaces they leave, to measure meshes against.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "dexelmill/stock/tridexel.h"

namespace dexelmill::testing {

/// @brief A solid to remove from the stock: a membership test, and the unsigned distances to the
/// (unbounded) primitive surfaces that bound it.
struct Cutter {
    std::function<bool(const Vec3&)> inside;
    std::vector<std::function<double(const Vec3&)>> surfaces;
};

/// @brief Sphere of radius r about c.
inline Cutter sphere(Vec3 c, double r) {
    return {[=](const Vec3& p) { return glm::length(p - c) < r; },
            {[=](const Vec3& p) { return std::abs(glm::length(p - c) - r); }}};
}

/// @brief Infinite cylinder of radius r about the line through c along dir.
inline Cutter cylinder(Vec3 c, Vec3 dir, double r) {
    dir = glm::normalize(dir);
    auto rho = [=](const Vec3& p) {
        const Vec3 d = p - c;
        return glm::length(d - glm::dot(d, dir) * dir);
    };
    return {[=](const Vec3& p) { return rho(p) < r; },
            {[=](const Vec3& p) { return std::abs(rho(p) - r); }}};
}

/// @brief Torus about the axis through c along n: major radius R, minor radius r.
inline Cutter torus(Vec3 c, Vec3 n, double R, double r) {
    n = glm::normalize(n);
    auto tube = [=](const Vec3& p) {
        const Vec3 d = p - c;
        const double z = glm::dot(d, n);
        const double rho = glm::length(d - z * n);
        return std::hypot(rho - R, z);
    };
    return {[=](const Vec3& p) { return tube(p) < r; },
            {[=](const Vec3& p) { return std::abs(tube(p) - r); }}};
}

/// @brief A box (a pocket when it reaches above the stock): its six face planes are surfaces.
inline Cutter boxCutter(Box b) {
    Cutter cut{[=](const Vec3& p) {
                   return p.x > b.lo.x && p.x < b.hi.x && p.y > b.lo.y && p.y < b.hi.y &&
                          p.z > b.lo.z && p.z < b.hi.z;
               },
               {}};
    for (int a = 0; a < 3; ++a) {
        cut.surfaces.push_back([=](const Vec3& p) { return std::abs(p[a] - b.lo[a]); });
        cut.surfaces.push_back([=](const Vec3& p) { return std::abs(p[a] - b.hi[a]); });
    }
    return cut;
}

/// @brief Removes `cut` from every dexel of the stock: along each dexel line the runs inside the
/// cutter are found by sampling every h/16 and bisecting each end to 1e-12 mm.
inline void carve(TriDexelStock& stock, const Cutter& cut) {
    const Lattice& lat = stock.lattice();
    const double h = lat.h;
    for (int a = 0; a < 3; ++a) {
        const Axis axis = axisFromIndex(a);
        if (!stock.has(axis)) continue;
        DexelFamily& fam = stock.family(axis);
        const double len = lat.n[a] * h;
        const double step = h / 16.0;
        const int samples = int(std::ceil((len + 2 * h) / step));
        for (int ic = 0; ic < fam.nc(); ++ic) {
            for (int ib = 0; ib < fam.nb(); ++ib) {
                const Line line = stock.dexelLine(axis, ib, ic);
                auto in = [&](double v) { return cut.inside(line.at(v)); };
                auto edge = [&](double lo, double hi) {  // in(lo) != in(hi)
                    const bool inLo = in(lo);
                    for (int it = 0; it < 200 && hi - lo > 1e-12; ++it) {
                        const double mid = 0.5 * (lo + hi);
                        (in(mid) == inLo ? lo : hi) = mid;
                    }
                    return 0.5 * (lo + hi);
                };
                double v = -h, start = 0.0;
                bool was = in(v);
                if (was) start = v;
                for (int s = 1; s <= samples; ++s) {
                    const double w = -h + s * step;
                    const bool now = in(w);
                    if (now != was) {
                        const double e = edge(v, w);
                        if (now) start = e;
                        else fam.subtract(ib, ic, float(start), float(e));
                    }
                    was = now;
                    v = w;
                }
                if (was) fam.subtract(ib, ic, float(start), float(v));
            }
        }
    }
}

/// @brief The exact surfaces of a carved box: the box's face planes and every cutter's.
struct PartSurfaces {
    std::vector<std::function<double(const Vec3&)>> surfaces;

    PartSurfaces(const Box& box, const std::vector<Cutter>& cuts) {
        for (const Cutter& c : {boxCutter(box)})
            surfaces.insert(surfaces.end(), c.surfaces.begin(), c.surfaces.end());
        for (const Cutter& c : cuts)
            surfaces.insert(surfaces.end(), c.surfaces.begin(), c.surfaces.end());
    }

    /// @brief Distance of p to the nearest surface, and whether a second surface passes within
    /// `featureBand` (p is then near a sharp edge, where the tests do not measure).
    std::pair<double, bool> measure(const Vec3& p, double featureBand) const {
        double d1 = std::numeric_limits<double>::infinity(), d2 = d1;
        for (const auto& s : surfaces) {
            const double d = s(p);
            if (d < d1) {
                d2 = d1;
                d1 = d;
            } else if (d < d2) {
                d2 = d;
            }
        }
        return {d1, d2 < featureBand};
    }
};

}  // namespace dexelmill::testing
