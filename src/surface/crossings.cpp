#include "surface/detail/crossings.h"

#include <algorithm>
#include <atomic>
#include <mutex>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "geometry/detail/coarse_grid.h"

namespace dexelmill::detail {

namespace {

/// Whether the segment pq crosses triangle t (unit normal u): its ends lie either side of t's
/// plane by more than tol, and the point where it passes lies inside each of t's edges by more
/// than tol.
bool edgeCrosses(const Vec3& p, const Vec3& q, const std::array<Vec3, 3>& t, const Vec3& u,
                 double tol) {
    const double dp = glm::dot(u, p - t[0]), dq = glm::dot(u, q - t[0]);
    if (!((dp > tol && dq < -tol) || (dp < -tol && dq > tol))) return false;
    const Vec3 x = p + (dp / (dp - dq)) * (q - p);
    for (int k = 0; k < 3; ++k) {
        const Vec3 e = t[std::size_t((k + 1) % 3)] - t[std::size_t(k)];
        const double length = glm::length(e);
        // The distance of x from the edge's line, in the plane, positive on the triangle's side.
        if (!(length > 0.0) || !(glm::dot(glm::cross(e, x - t[std::size_t(k)]), u) > tol * length))
            return false;
    }
    return true;
}

/// The unit normal of triangle t, or 0 if it has no area.
Vec3 unitNormal(const std::array<Vec3, 3>& t) {
    const Vec3 n = glm::cross(t[1] - t[0], t[2] - t[0]);
    const double area2 = glm::length(n);
    return area2 > 0.0 ? n / area2 : Vec3(0.0);
}

/// Whether triangles a and b, in one plane (a's unit normal u), overlap in more than the corners
/// and edge they share: an edge of one crossing an edge of the other, a corner of one inside the
/// other, the same corners, or, sharing an edge, the other corners on the same side of it (one
/// folded onto the other); each by more than tol.
bool overlapInPlane(const std::array<std::uint32_t, 3>& ia, const std::array<Vec3, 3>& a,
                    const std::array<std::uint32_t, 3>& ib, const std::array<Vec3, 3>& b,
                    const Vec3& u, double tol) {
    // The distance of p from the line through e0 and e1, in the plane: positive to the left of
    // e0 -> e1 seen from u's side.
    const auto side = [&](const Vec3& e0, const Vec3& e1, const Vec3& p) {
        const Vec3 e = e1 - e0;
        const double length = glm::length(e);
        return length > 0.0 ? glm::dot(glm::cross(e, p - e0), u) / length : 0.0;
    };
    const auto sharedBy = [](const std::array<std::uint32_t, 3>& ids, std::uint32_t v) {
        return ids[0] == v || ids[1] == v || ids[2] == v;
    };
    int shared = 0;
    for (std::uint32_t v : ia) shared += sharedBy(ib, v);
    if (shared == 3) return true;
    if (shared == 2) {
        std::size_t oa = 0, ob = 0;
        while (sharedBy(ib, ia[oa])) ++oa;
        while (sharedBy(ia, ib[ob])) ++ob;
        const Vec3& e0 = a[(oa + 1) % 3];
        const Vec3& e1 = a[(oa + 2) % 3];
        const double sa = side(e0, e1, a[oa]), sb = side(e0, e1, b[ob]);
        return (sa > tol && sb > tol) || (sa < -tol && sb < -tol);
    }
    const auto strictlyApart = [&](double x, double y) {
        return (x > tol && y < -tol) || (x < -tol && y > tol);
    };
    for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t j = 0; j < 3; ++j) {
            const Vec3 &p0 = a[i], &p1 = a[(i + 1) % 3], &q0 = b[j], &q1 = b[(j + 1) % 3];
            if (strictlyApart(side(p0, p1, q0), side(p0, p1, q1)) &&
                strictlyApart(side(q0, q1, p0), side(q0, q1, p1)))
                return true;
        }
    const auto inside = [&](const std::array<Vec3, 3>& t, const Vec3& p) {
        const double s0 = side(t[0], t[1], p), s1 = side(t[1], t[2], p), s2 = side(t[2], t[0], p);
        return (s0 > tol && s1 > tol && s2 > tol) || (s0 < -tol && s1 < -tol && s2 < -tol);
    };
    for (std::size_t k = 0; k < 3; ++k) {
        if (!sharedBy(ib, ia[k]) && inside(b, a[k])) return true;
        if (!sharedBy(ia, ib[k]) && inside(a, b[k])) return true;
    }
    return false;
}

std::array<Vec3, 3> corners(const Mesh& mesh, const Mesh::Triangle& t) {
    return {mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]};
}

/// The relative padding of a float box's coordinates (crossingTriangles): 2^-20.
constexpr double kFloatPad = 1.0 / 1048576.0;

Box boxOf(const std::array<Vec3, 3>& p) {
    Box b;
    for (const Vec3& v : p) b.expand(v);
    return b;
}

}  // namespace

namespace {

/// trianglesCross with a's unit normal given (unitNormal: zero for no area), so that a triangle
/// tested against many makes it once.
bool crossWithNormal(const std::array<std::uint32_t, 3>& ia, const std::array<Vec3, 3>& a,
                     const Vec3& ua, const std::array<std::uint32_t, 3>& ib,
                     const std::array<Vec3, 3>& b, double tol) {
    int shared = 0, sa = 0, sb = 0;
    std::array<bool, 3> aShared{}, bShared{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (ia[std::size_t(i)] == ib[std::size_t(j)])
                ++shared, sa = i, sb = j, aShared[std::size_t(i)] = bShared[std::size_t(j)] = true;
    // Each triangle's corners against the other's plane (a shared corner lies on both): all on one
    // side, the pair cannot meet but in what it shares.
    const auto sides = [&](const std::array<Vec3, 3>& t, const std::array<Vec3, 3>& other,
                           const std::array<bool, 3>& sharedCorner, const Vec3& u, bool& flat) {
        bool above = true, below = true;
        flat = true;
        for (std::size_t k = 0; k < 3; ++k) {
            const double d = sharedCorner[k] ? 0.0 : glm::dot(u, other[k] - t[0]);
            above = above && d > tol;
            below = below && d < -tol;
            flat = flat && std::abs(d) <= tol;
        }
        return above || below;
    };
    if (ua == Vec3(0.0)) return false;
    bool bFlat = false, aFlat = false;
    if (sides(a, b, bShared, ua, bFlat)) return false;
    if (shared >= 2 && !bFlat) return false;  // out of one plane, they meet only along the edge
    const Vec3 ub = unitNormal(b);
    if (ub == Vec3(0.0) || sides(b, a, aShared, ub, aFlat)) return false;
    if (aFlat && bFlat) return overlapInPlane(ia, a, ib, b, ua, tol);
    if (shared >= 2) return false;
    const auto at = [](const std::array<Vec3, 3>& t, int k) { return t[std::size_t(k % 3)]; };
    if (shared == 1)
        return edgeCrosses(at(a, sa + 1), at(a, sa + 2), b, ub, tol) ||
               edgeCrosses(at(b, sb + 1), at(b, sb + 2), a, ua, tol);
    for (int k = 0; k < 3; ++k)
        if (edgeCrosses(at(a, k), at(a, k + 1), b, ub, tol) ||
            edgeCrosses(at(b, k), at(b, k + 1), a, ua, tol))
            return true;
    return false;
}

}  // namespace

bool trianglesCross(const std::array<std::uint32_t, 3>& ia, const std::array<Vec3, 3>& a,
                    const std::array<std::uint32_t, 3>& ib, const std::array<Vec3, 3>& b,
                    double tol) {
    return crossWithNormal(ia, a, unitNormal(a), ib, b, tol);
}

std::vector<std::pair<int, int>> fanCrossings(const Mesh::Triangle* a, int na,
                                              const Mesh::Triangle* b, int nb, const Vec3* points,
                                              double tol) {
    const auto at = [&](const Mesh::Triangle& t) {
        return std::array<Vec3, 3>{points[t[0]], points[t[1]], points[t[2]]};
    };
    std::vector<std::pair<int, int>> out;
    for (int i = 0; i < na; ++i)
        for (int j = 0; j < nb; ++j)
            if (trianglesCross(a[i], at(a[i]), b[j], at(b[j]), tol)) out.push_back({i, j});
    return out;
}

std::vector<std::uint32_t> crossingTriangles(const Mesh& mesh,
                                             const std::vector<std::uint32_t>& pieces,
                                             const std::vector<std::uint32_t>& partners,
                                             double tol) {
    std::vector<std::uint32_t> found;
    if (pieces.empty()) return found;
    // The pieces' boxes, grown by tol and rounded outwards to float (padded by 2^-20 of each
    // coordinate, above float's relative rounding of 2^-24: a box may only grow; the product by a
    // power of two is exact), and a grid of cells about as large as an average box, each listing
    // the pieces whose boxes overlap it.
    struct FloatBox {
        std::array<float, 3> lo, hi;
    };
    const auto floatBox = [&](const Box& b) {
        FloatBox f;
        for (int a = 0; a < 3; ++a) {
            f.lo[std::size_t(a)] = float(b.lo[a] - tol - std::abs(b.lo[a]) * kFloatPad);
            f.hi[std::size_t(a)] = float(b.hi[a] + tol + std::abs(b.hi[a]) * kFloatPad);
        }
        return f;
    };
    std::vector<FloatBox> boxes(pieces.size());
    struct Sum {
        Box all;
        double extents = 0.0;
    };
    const Sum sum = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, pieces.size()), Sum{},
        [&](const tbb::blocked_range<std::size_t>& r, Sum acc) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const Box b = boxOf(corners(mesh, mesh.triangles[pieces[i]]));
                boxes[i] = floatBox(b);
                acc.all.expand(b);
                const Vec3 size = b.size();
                acc.extents += std::max({size.x, size.y, size.z});
            }
            return acc;
        },
        [](Sum a, const Sum& b) {
            a.all.expand(b.all);
            a.extents += b.extents;
            return a;
        });
    const CoarseGrid grid(sum.all.padded(tol), std::max(sum.extents / double(pieces.size()), 1e-6));
    const FloatBox reach = floatBox(sum.all);  // every piece's box lies inside it
    const double inverse = 1.0 / grid.size;
    // The cell coordinate along axis a of x, clamped to the grid (CoarseGrid::coord, inline).
    const auto coord = [&](int a, float x) {
        const double c = std::floor((double(x) - grid.origin[a]) * inverse);
        return c < 0.0                               ? 0
               : c >= double(grid.n[std::size_t(a)]) ? grid.n[std::size_t(a)] - 1
                                                     : int(c);
    };
    const auto cells = [&](const FloatBox& b, std::array<int, 3>& c0, std::array<int, 3>& c1) {
        for (int a = 0; a < 3; ++a) {
            c0[std::size_t(a)] = coord(a, b.lo[std::size_t(a)]);
            c1[std::size_t(a)] = coord(a, b.hi[std::size_t(a)]);
        }
    };
    const auto eachCell = [&](const FloatBox& b, auto&& visit) {
        std::array<int, 3> c0{}, c1{};
        cells(b, c0, c1);
        for (int z = c0[2]; z <= c1[2]; ++z)
            for (int y = c0[1]; y <= c1[1]; ++y)
                for (int x = c0[0]; x <= c1[0]; ++x) visit(grid.index({x, y, z}));
    };
    // Counted and filled in parallel; each cell's list is then sorted, as the pair loop needs.
    std::vector<std::atomic<std::uint32_t>> count(grid.cellCount());
    tbb::parallel_for(std::size_t(0), boxes.size(), [&](std::size_t i) {
        eachCell(boxes[i],
                 [&](std::size_t c) { count[c].fetch_add(1, std::memory_order_relaxed); });
    });
    std::vector<std::uint32_t> start(grid.cellCount() + 1, 0);
    for (std::size_t c = 0; c < count.size(); ++c) {
        start[c + 1] = start[c] + count[c].load(std::memory_order_relaxed);
        count[c].store(start[c], std::memory_order_relaxed);
    }
    std::vector<std::uint32_t> inCell(start.back());
    tbb::parallel_for(std::size_t(0), boxes.size(), [&](std::size_t i) {
        eachCell(boxes[i], [&](std::size_t c) {
            inCell[count[c].fetch_add(1, std::memory_order_relaxed)] = std::uint32_t(i);
        });
    });
    tbb::parallel_for(std::size_t(0), grid.cellCount(), [&](std::size_t c) {
        if (start[c + 1] - start[c] > 1)
            std::sort(inCell.begin() + start[c], inCell.begin() + start[c + 1]);
    });

    std::mutex lock;
    tbb::parallel_for(std::size_t(0), partners.size(), [&](std::size_t k) {
        const std::uint32_t t = partners[k];
        const Mesh::Triangle& ti = mesh.triangles[t];
        const std::array<Vec3, 3> tp = corners(mesh, ti);
        const FloatBox tb = floatBox(boxOf(tp));
        for (std::size_t a = 0; a < 3; ++a)
            if (tb.lo[a] > reach.hi[a] || reach.lo[a] > tb.hi[a]) return;
        bool haveNormal = false;  // t's, made when a box first overlaps
        Vec3 tn(0.0);
        // t's index among the pieces (their count if it is none): a pair of pieces is tested once,
        // from the later, and a cell lists its pieces in order.
        const auto it = std::lower_bound(pieces.begin(), pieces.end(), t);
        const std::size_t self =
            it != pieces.end() && *it == t ? std::size_t(it - pieces.begin()) : pieces.size();
        eachCell(tb, [&](std::size_t c) {
            for (std::uint32_t j = start[c]; j < start[c + 1]; ++j) {
                const std::uint32_t i = inCell[j];
                if (i >= self) break;
                const FloatBox& pb = boxes[i];
                std::array<float, 3> lo{};
                bool apart = false;
                for (std::size_t a = 0; a < 3; ++a) {
                    apart = apart || tb.lo[a] > pb.hi[a] || pb.lo[a] > tb.hi[a];
                    lo[a] = std::max(tb.lo[a], pb.lo[a]);
                }
                if (apart) continue;
                // A pair in several cells is tested in the first both boxes overlap.
                if (grid.index({coord(0, lo[0]), coord(1, lo[1]), coord(2, lo[2])}) != c) continue;
                if (!haveNormal) tn = unitNormal(tp), haveNormal = true;
                const std::uint32_t p = pieces[i];
                const Mesh::Triangle& pi = mesh.triangles[p];
                if (!crossWithNormal(ti, tp, tn, pi, corners(mesh, pi), tol)) continue;
                const std::lock_guard<std::mutex> guard(lock);
                found.push_back(t);
                found.push_back(p);
            }
        });
    });
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
    return found;
}

}  // namespace dexelmill::detail
