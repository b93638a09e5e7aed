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

/// @brief A solid to remove from the stock: a membership test, its outward unit normal at a
/// boundary point, and the unsigned distances to the (unbounded) primitive surfaces that bound it.
struct Cutter {
    std::function<bool(const Vec3&)> inside;
    std::vector<std::function<double(const Vec3&)>> surfaces;
    std::function<Vec3(const Vec3&)> normal;
};

/// @brief Sphere of radius r about c.
inline Cutter sphere(Vec3 c, double r) {
    return {[=](const Vec3& p) { return glm::length(p - c) < r; },
            {[=](const Vec3& p) { return std::abs(glm::length(p - c) - r); }},
            [=](const Vec3& p) { return glm::normalize(p - c); }};
}

/// @brief Infinite cylinder of radius r about the line through c along dir.
inline Cutter cylinder(Vec3 c, Vec3 dir, double r) {
    dir = glm::normalize(dir);
    auto radial = [=](const Vec3& p) {
        const Vec3 d = p - c;
        return d - glm::dot(d, dir) * dir;
    };
    return {[=](const Vec3& p) { return glm::length(radial(p)) < r; },
            {[=](const Vec3& p) { return std::abs(glm::length(radial(p)) - r); }},
            [=](const Vec3& p) { return glm::normalize(radial(p)); }};
}

/// @brief The capsule of radius r around the segment a-b: a ball end mill's pass.
inline Cutter capsule(Vec3 a, Vec3 b, double r) {
    auto nearest = [=](const Vec3& p) {
        const Vec3 ab = b - a;
        const double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
        return a + t * ab;
    };
    return {[=](const Vec3& p) { return glm::length(p - nearest(p)) < r; },
            {[=](const Vec3& p) { return std::abs(glm::length(p - nearest(p)) - r); }},
            [=](const Vec3& p) { return glm::normalize(p - nearest(p)); }};
}

/// @brief Torus about the axis through c along n: major radius R, minor radius r.
inline Cutter torus(Vec3 c, Vec3 n, double R, double r) {
    n = glm::normalize(n);
    auto tubeCentre = [=](const Vec3& p) {
        const Vec3 d = p - c;
        const Vec3 radial = d - glm::dot(d, n) * n;
        return c + R * glm::normalize(radial);
    };
    return {[=](const Vec3& p) { return glm::length(p - tubeCentre(p)) < r; },
            {[=](const Vec3& p) { return std::abs(glm::length(p - tubeCentre(p)) - r); }},
            [=](const Vec3& p) { return glm::normalize(p - tubeCentre(p)); }};
}

/// @brief The intersection of half-spaces {x : n_i . x < d_i} (n_i unit, outward): a wedge, a
/// V-groove, a slab. At a boundary point the normal is that of the constraint nearest to binding.
inline Cutter halfSpaces(std::vector<std::pair<Vec3, double>> planes) {
    for (auto& [n, d] : planes) {
        const double l = glm::length(n);
        n /= l;
        d /= l;
    }
    Cutter cut{[=](const Vec3& p) {
                   for (const auto& [n, d] : planes)
                       if (!(glm::dot(n, p) < d)) return false;
                   return true;
               },
               {},
               [=](const Vec3& p) {
                   double best = -std::numeric_limits<double>::infinity();
                   Vec3 out(0.0);
                   for (const auto& [n, d] : planes)
                       if (glm::dot(n, p) - d > best) best = glm::dot(n, p) - d, out = n;
                   return out;
               }};
    for (const auto& [n, d] : planes)
        cut.surfaces.push_back([n = n, d = d](const Vec3& p) { return std::abs(glm::dot(n, p) - d); });
    return cut;
}

/// @brief A box (a pocket when it reaches above the stock): its six face planes are surfaces.
inline Cutter boxCutter(Box b) {
    std::vector<std::pair<Vec3, double>> planes;
    for (int a = 0; a < 3; ++a) {
        Vec3 n(0.0);
        n[a] = 1.0;
        planes.push_back({n, b.hi[a]});
        planes.push_back({-n, -b.lo[a]});
    }
    return halfSpaces(planes);
}

/// @brief Removes `c` from every dexel of the stock: along each dexel line the runs inside the
/// cutter are found by sampling every h/16 and bisecting each end to 1e-12 mm; the new ends take
/// the cutter's normal, reversed.
inline void carve(TriDexelStock& stock, const Cutter& c) {
    const Lattice& lat = stock.lattice();
    const double h = lat.h;
    for (int a = 0; a < 3; ++a) {
        const Axis axis = axisFromIndex(a);
        if (!stock.has(axis)) continue;
        DexelFamily& fam = stock.family(axis);
        const double len = lat.n[a] * h;
        const double step = h / 16.0;
        const int samples = int(std::ceil((len + 2 * h) / step));
        // The material left at a cut's ends faces the cutter: its normal is the cutter's, reversed.
        auto cut = [&](int ib, int ic, const Line& line, double lo, double hi) {
            fam.subtract(ib, ic, float(lo), float(hi), PackedNormal::pack(-c.normal(line.at(lo))),
                         PackedNormal::pack(-c.normal(line.at(hi))));
        };
        for (int ic = 0; ic < fam.nc(); ++ic) {
            for (int ib = 0; ib < fam.nb(); ++ib) {
                const Line line = stock.dexelLine(axis, ib, ic);
                auto in = [&](double v) { return c.inside(line.at(v)); };
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
                        else cut(ib, ic, line, start, e);
                    }
                    was = now;
                    v = w;
                }
                if (was) cut(ib, ic, line, start, v);
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
