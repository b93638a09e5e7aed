/// @file self_intersection.h
/// @brief Test support: a brute-force count of the pairs of a mesh's triangles that meet where they
/// should not, sharing no code with the library's meshers or checks.
///
/// Two triangles of a mesh may meet only in what they share by index: a corner or an edge. Any
/// other contact of positive length or area is a self-intersection. Pairs are found through a
/// uniform grid of their boxes and tested one by one:
///  - **Not coplanar.** Each triangle meets the other's plane in a segment of the line where the
///    planes cross (Moller's interval test); the triangles meet where the two segments overlap. A
///    shared corner lies on both segments, so the overlap counts only where it is longer than the
///    tolerance; a shared edge is all that two such triangles can have in common.
///  - **Coplanar** (every corner of one within the tolerance of the other's plane, or normals
///  within
///    1e-12 rad): in the plane, an edge of one properly crossing an edge of the other, a corner of
///    one strictly inside the other, or the same three corners.
/// The tolerance is 1e-9 of the mesh's bounding box diagonal: contacts shorter than that (about
/// 5e-8 mm on a 50 mm part) are not counted, and neither are triangles of zero area (checkMesh
/// counts those).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "dexelmill/surface/mesh.h"

namespace dexelmill::testing {

/// @brief What countSelfIntersections found.
struct SelfIntersections {
    std::size_t pairs = 0;   ///< pairs of triangles that meet other than in what they share
    std::size_t tested = 0;  ///< pairs whose boxes overlap, tested exactly
    std::array<std::uint32_t, 2> first{0, 0};        ///< the first such pair found
    Vec3 at{0.0};                                    ///< a corner of its first triangle
    std::vector<std::array<std::uint32_t, 2>> some;  ///< the first kMaxListed pairs found
    static constexpr std::size_t kMaxListed = 64;
};

namespace self_intersection_detail {

struct Tri {
    std::array<Vec3, 3> p;
    std::array<std::uint32_t, 3> id;
    Vec3 n;  ///< unit normal
};

/// Twice the signed area of (a, b, c) in the plane of axes (i, j), divided by |b - a|: the signed
/// distance of c from the line through a and b (0 where a = b).
inline double side2(const Vec3& a, const Vec3& b, const Vec3& c, int i, int j) {
    const double ex = b[i] - a[i], ey = b[j] - a[j];
    const double len = std::hypot(ex, ey);
    return len > 0.0 ? (ex * (c[j] - a[j]) - ey * (c[i] - a[i])) / len : 0.0;
}

/// Whether coplanar triangles overlap in more than shared corners and edges (see the file's note).
inline bool coplanarOverlap(const Tri& a, const Tri& b, int shared, double tol) {
    if (shared == 3) return true;
    // Drop the axis along which the normal is largest.
    int drop = 0;
    for (int k = 1; k < 3; ++k)
        if (std::abs(a.n[k]) > std::abs(a.n[drop])) drop = k;
    const int i = (drop + 1) % 3, j = (drop + 2) % 3;
    for (int e = 0; e < 3; ++e)
        for (int f = 0; f < 3; ++f) {
            const Vec3 &p0 = a.p[e], &p1 = a.p[(e + 1) % 3], &q0 = b.p[f], &q1 = b.p[(f + 1) % 3];
            const double s0 = side2(p0, p1, q0, i, j), s1 = side2(p0, p1, q1, i, j);
            const double t0 = side2(q0, q1, p0, i, j), t1 = side2(q0, q1, p1, i, j);
            if (((s0 > tol && s1 < -tol) || (s0 < -tol && s1 > tol)) &&
                ((t0 > tol && t1 < -tol) || (t0 < -tol && t1 > tol)))
                return true;
        }
    const auto strictlyInside = [&](const Tri& t, const Vec3& c) {
        const double s0 = side2(t.p[0], t.p[1], c, i, j), s1 = side2(t.p[1], t.p[2], c, i, j),
                     s2 = side2(t.p[2], t.p[0], c, i, j);
        return (s0 > tol && s1 > tol && s2 > tol) || (s0 < -tol && s1 < -tol && s2 < -tol);
    };
    for (int k = 0; k < 3; ++k) {
        if (std::find(b.id.begin(), b.id.end(), a.id[k]) == b.id.end() && strictlyInside(b, a.p[k]))
            return true;
        if (std::find(a.id.begin(), a.id.end(), b.id[k]) == a.id.end() && strictlyInside(a, b.p[k]))
            return true;
    }
    return false;
}

/// The interval of line parameters (along the unit direction d) where triangle t meets the plane
/// from which its corners' signed distances are `dist` (exactly 0 for a shared corner); false if
/// it does not.
inline bool planeInterval(const Tri& t, const std::array<double, 3>& dist, const Vec3& d,
                          double& lo, double& hi) {
    lo = INFINITY;
    hi = -INFINITY;
    for (int k = 0; k < 3; ++k) {
        const double pk = glm::dot(d, t.p[k]);
        if (dist[k] == 0.0) lo = std::min(lo, pk), hi = std::max(hi, pk);
        const int m = (k + 1) % 3;
        if ((dist[k] > 0.0 && dist[m] < 0.0) || (dist[k] < 0.0 && dist[m] > 0.0)) {
            const double pm = glm::dot(d, t.p[m]);
            const double x = pk + (pm - pk) * dist[k] / (dist[k] - dist[m]);
            lo = std::min(lo, x), hi = std::max(hi, x);
        }
    }
    return lo <= hi;
}

/// Whether triangles a and b meet in more than what they share.
inline bool meet(const Tri& a, const Tri& b, double tol) {
    int shared = 0;
    for (std::uint32_t x : a.id) shared += int(std::count(b.id.begin(), b.id.end(), x));
    std::array<double, 3> da{}, db{};  // a's corners from b's plane, b's from a's
    bool aFlat = true, bFlat = true;
    // A shared corner lies on both planes: exactly 0. Other distances are kept as they are, so
    // that the segments below are those of the triangles as they lie (a corner within the
    // tolerance of the other's plane but not on it is not moved onto it).
    for (int k = 0; k < 3; ++k) {
        const bool bShared = std::find(a.id.begin(), a.id.end(), b.id[k]) != a.id.end();
        const bool aShared = std::find(b.id.begin(), b.id.end(), a.id[k]) != b.id.end();
        db[k] = bShared ? 0.0 : glm::dot(a.n, b.p[k] - a.p[0]);
        da[k] = aShared ? 0.0 : glm::dot(b.n, a.p[k] - b.p[0]);
        bFlat = bFlat && std::abs(db[k]) <= tol;
        aFlat = aFlat && std::abs(da[k]) <= tol;
    }
    const Vec3 cross = glm::cross(a.n, b.n);
    const double sine = glm::length(cross);
    if (sine < 1e-12 || aFlat || bFlat) {
        // Parallel planes apart never meet. Otherwise the pair lies in one plane (a triangle within
        // the tolerance of the other's plane, but not the other way round, is a sliver).
        if (!aFlat && !bFlat) return false;
        return coplanarOverlap(a, b, shared, tol);
    }
    const auto oneSide = [](const std::array<double, 3>& d) {
        return (d[0] > 0.0 && d[1] > 0.0 && d[2] > 0.0) || (d[0] < 0.0 && d[1] < 0.0 && d[2] < 0.0);
    };
    if (oneSide(db) || oneSide(da)) return false;
    if (shared == 2) return false;  // not coplanar: they meet in the shared edge alone
    const Vec3 d = cross / sine;
    double alo = 0.0, ahi = 0.0, blo = 0.0, bhi = 0.0;
    if (!planeInterval(a, da, d, alo, ahi) || !planeInterval(b, db, d, blo, bhi)) return false;
    return std::min(ahi, bhi) - std::max(alo, blo) > tol;
}

}  // namespace self_intersection_detail

/// @brief Counts the pairs of triangles of `mesh` that meet other than in the corners and edges
/// they share by index (see the file's note).
inline SelfIntersections countSelfIntersections(const Mesh& mesh) {
    namespace sid = self_intersection_detail;
    SelfIntersections out;
    if (mesh.triangles.empty()) return out;
    Vec3 lo(INFINITY), hi(-INFINITY);
    for (const Vec3& v : mesh.vertices) lo = glm::min(lo, v), hi = glm::max(hi, v);
    const double tol = 1e-9 * glm::length(hi - lo);
    std::vector<sid::Tri> tris;
    std::vector<std::uint32_t> index;  // mesh triangle of each entry of tris
    double edges = 0.0;
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
        sid::Tri tri;
        for (int k = 0; k < 3; ++k)
            tri.id[k] = mesh.triangles[t][k], tri.p[k] = mesh.vertices[tri.id[k]];
        const Vec3 c = glm::cross(tri.p[1] - tri.p[0], tri.p[2] - tri.p[0]);
        const double area2 = glm::length(c);
        if (!(area2 > 0.0)) continue;
        tri.n = c / area2;
        for (int k = 0; k < 3; ++k) edges += glm::length(tri.p[(k + 1) % 3] - tri.p[k]);
        tris.push_back(tri);
        index.push_back(t);
    }
    if (tris.empty()) return out;
    const double cell = std::max(2.0 * edges / (3.0 * double(tris.size())), 1e-12);
    const auto cellOf = [&](const Vec3& p) {
        return std::array<std::int64_t, 3>{std::int64_t(std::floor((p.x - lo.x) / cell)),
                                           std::int64_t(std::floor((p.y - lo.y) / cell)),
                                           std::int64_t(std::floor((p.z - lo.z) / cell))};
    };
    const auto key = [](const std::array<std::int64_t, 3>& c) {
        return (std::uint64_t(c[0]) * 73856093u) ^ (std::uint64_t(c[1]) * 19349663u) ^
               (std::uint64_t(c[2]) * 83492791u);
    };
    struct Cell {
        std::array<std::int64_t, 3> c;
        std::vector<std::uint32_t> tris;
    };
    std::unordered_map<std::uint64_t, std::vector<Cell>> grid;
    std::vector<std::array<Vec3, 2>> boxes(tris.size());
    for (std::uint32_t t = 0; t < tris.size(); ++t) {
        Vec3 blo(INFINITY), bhi(-INFINITY);
        for (const Vec3& p : tris[t].p) blo = glm::min(blo, p), bhi = glm::max(bhi, p);
        blo -= Vec3(tol), bhi += Vec3(tol);
        boxes[t] = {blo, bhi};
        const auto c0 = cellOf(blo), c1 = cellOf(bhi);
        for (std::int64_t x = c0[0]; x <= c1[0]; ++x)
            for (std::int64_t y = c0[1]; y <= c1[1]; ++y)
                for (std::int64_t z = c0[2]; z <= c1[2]; ++z) {
                    const std::array<std::int64_t, 3> c{x, y, z};
                    std::vector<Cell>& bucket = grid[key(c)];
                    auto it = std::find_if(bucket.begin(), bucket.end(),
                                           [&](const Cell& e) { return e.c == c; });
                    if (it == bucket.end()) bucket.push_back({c, {}}), it = bucket.end() - 1;
                    it->tris.push_back(t);
                }
    }
    for (const auto& [k, bucket] : grid)
        for (const Cell& cell : bucket)
            for (std::size_t i = 0; i < cell.tris.size(); ++i)
                for (std::size_t j = i + 1; j < cell.tris.size(); ++j) {
                    const std::uint32_t a = cell.tris[i], b = cell.tris[j];
                    const Vec3 olo = glm::max(boxes[a][0], boxes[b][0]),
                               ohi = glm::min(boxes[a][1], boxes[b][1]);
                    if (olo.x > ohi.x || olo.y > ohi.y || olo.z > ohi.z) continue;
                    if (cellOf(olo) != cell.c)
                        continue;  // tested in the first cell the boxes share
                    ++out.tested;
                    if (!sid::meet(tris[a], tris[b], tol)) continue;
                    if (out.pairs++ == 0) out.first = {index[a], index[b]}, out.at = tris[a].p[0];
                    if (out.some.size() < SelfIntersections::kMaxListed)
                        out.some.push_back({index[a], index[b]});
                }
    return out;
}

}  // namespace dexelmill::testing
