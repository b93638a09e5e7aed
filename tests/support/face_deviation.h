/// @file face_deviation.h
/// @brief Test support: the exact part a box stock leaves after analytic cutters, and a measure
/// of a mesh against it that shares no code with the library: points spread evenly over the
/// triangles, each moved to the nearest change of exact membership and bisected there.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "dexelmill/surface/mesh.h"
#include "support/analytic_parts.h"

namespace dexelmill::testing {

/// The exact part: the stock box minus the cutters.
struct CarvedPart {
    Box box;
    std::vector<Cutter> cuts;

    bool inside(const Vec3& p) const {
        if (!(p.x > box.lo.x && p.x < box.hi.x && p.y > box.lo.y && p.y < box.hi.y && p.z > box.lo.z &&
              p.z < box.hi.z))
            return false;
        for (const Cutter& c : cuts)
            if (c.inside(p)) return false;
        return true;
    }
};

/// Distances (mm) of points spread over the mesh to the exact surface.
struct FaceDeviation {
    double rms = 0.0, p99 = 0.0, max = 0.0;
    std::size_t samples = 0, misses = 0;
    Vec3 worst{0.0};
};

/// The triangles in an order that depends only on the surface: by their corners (each triangle
/// turned to start at its least corner), so that the same surface listed in another order (a
/// mesher that walks its blocks differently) gets the same sample points.
inline std::vector<std::size_t> surfaceOrder(const Mesh& mesh) {
    using Corners = std::array<std::array<double, 3>, 3>;
    std::vector<Corners> key(mesh.triangles.size());
    for (std::size_t t = 0; t < key.size(); ++t) {
        Corners c;
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) c[std::size_t(k)][std::size_t(a)] = mesh.vertices[mesh.triangles[t][std::size_t(k)]][a];
        key[t] = std::min({c, Corners{c[1], c[2], c[0]}, Corners{c[2], c[0], c[1]}});
    }
    std::vector<std::size_t> order(key.size());
    for (std::size_t t = 0; t < order.size(); ++t) order[t] = t;
    std::sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return key[x] < key[y]; });
    return order;
}

/// Samples `count` points uniformly over the triangles' area (fixed seed, triangles in
/// surfaceOrder). Each is classified,
/// and the nearest change of membership is searched along its face normal and, so that a point
/// by a sharp edge of the part finds the other face too, along the axes and the cube diagonals:
/// steps of reach / 48 in both directions of each, the first change bisected to 1e-10 mm. The
/// least distance found is an upper bound of the point's distance to the surface, exact on a
/// face. A point with no change within reach counts as `reach`. A mesh without triangles has no
/// samples.
inline FaceDeviation measureFaces(const Mesh& mesh, const CarvedPart& part, double reach, std::size_t count = 20000) {
    if (mesh.triangles.empty()) return {};
    const std::vector<std::size_t> order = surfaceOrder(mesh);
    std::vector<double> cumulative;
    double total = 0.0;
    for (std::size_t t : order) {
        total += 0.5 * glm::length(mesh.areaVector(t));
        cumulative.push_back(total);
    }
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<double> d;
    FaceDeviation out;
    for (std::size_t s = 0; s < count; ++s) {
        const std::size_t t = std::size_t(std::lower_bound(cumulative.begin(), cumulative.end(), unit(rng) * total) -
                                          cumulative.begin());
        const Mesh::Triangle& tri = mesh.triangles[order[std::min(t, order.size() - 1)]];
        double r1 = unit(rng), r2 = unit(rng);
        if (r1 + r2 > 1.0) r1 = 1.0 - r1, r2 = 1.0 - r2;
        const Vec3 &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
        const Vec3 x = a + r1 * (b - a) + r2 * (c - a);
        const Vec3 normal = glm::normalize(glm::cross(b - a, c - a));
        const bool in0 = part.inside(x);
        double found = reach;
        bool hit = false;
        const double step = reach / 48.0;
        std::vector<Vec3> dirs{normal};
        for (int axis = 0; axis < 3; ++axis) {
            Vec3 e(0.0);
            e[axis] = 1.0;
            dirs.push_back(e);
        }
        for (double sy : {1.0, -1.0})
            for (double sz : {1.0, -1.0}) dirs.push_back(glm::normalize(Vec3(1.0, sy, sz)));
        for (const Vec3& n : dirs) {
            bool found1 = false;
            for (int k = 1; k <= 48 && !found1 && k * step < found; ++k) {
                for (double sgn : {1.0, -1.0}) {
                    if (part.inside(x + sgn * k * step * n) == in0) continue;
                    double lo = (k - 1) * step, hi = k * step;
                    while (hi - lo > 1e-10) {
                        const double mid = 0.5 * (lo + hi);
                        (part.inside(x + sgn * mid * n) == in0 ? lo : hi) = mid;
                    }
                    found = std::min(found, 0.5 * (lo + hi));
                    hit = found1 = true;
                }
            }
        }
        if (!hit) ++out.misses;
        if (found > out.max) { out.max = found; out.worst = x; }
        d.push_back(found);
    }
    std::sort(d.begin(), d.end());
    double sum2 = 0.0;
    for (double v : d) sum2 += v * v;
    out.samples = d.size();
    out.rms = std::sqrt(sum2 / double(d.size()));
    out.p99 = d[std::size_t(0.99 * double(d.size() - 1))];
    out.max = d.back();
    return out;
}

}  // namespace dexelmill::testing
