#include "dexelmill/surface/feature_snap.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace dexelmill {

namespace {

/// A neighbouring dexel's crossing counts as the same surface when it lies within this many h
/// of the crossing (a slope of 3, 72 degrees from the dexel axis).
constexpr double kNeighbourReach = 3.0;

/// A crossing: where, and the surface normal estimated there (zero if unknown).
struct Crossing {
    Vec3 p;
    Vec3 n;
};

/// The endpoint of the same kind (lo or hi) on dexel (ib, ic) nearest to t, within `reach`;
/// NaN if none.
double nearestEndpoint(const DexelFamily& fam, int ib, int ic, bool lo, double t, double reach) {
    if (ib < 0 || ic < 0 || ib >= fam.nb() || ic >= fam.nc()) return std::nan("");
    double best = std::nan(""), bestD = reach;
    for (const Segment& s : fam.segments(ib, ic)) {
        const double e = lo ? s.lo : s.hi;
        const double d = std::abs(e - t);
        if (d <= bestD) {
            bestD = d;
            best = e;
        }
    }
    return best;
}

/// The slope de/ds along one neighbour direction: of the two one-sided differences the one of
/// smaller magnitude (ENO), so the estimate does not reach across a sharp edge; NaN if neither.
double enoSlope(double minus, double e, double plus, double h) {
    const double dm = std::isnan(minus) ? std::nan("") : (e - minus) / h;
    const double dp = std::isnan(plus) ? std::nan("") : (plus - e) / h;
    if (std::isnan(dm)) return dp;
    if (std::isnan(dp)) return dm;
    return std::abs(dm) <= std::abs(dp) ? dm : dp;
}

/// Symmetric 3x3 eigen-decomposition by Jacobi rotations: a = V diag(w) V^T.
void symmetricEigen(double a[3][3], double w[3], double v[3][3]) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) v[i][j] = i == j ? 1.0 : 0.0;
    for (int sweep = 0; sweep < 32; ++sweep) {
        const double off = std::abs(a[0][1]) + std::abs(a[0][2]) + std::abs(a[1][2]);
        if (off < 1e-15 * (std::abs(a[0][0]) + std::abs(a[1][1]) + std::abs(a[2][2]) + 1e-300))
            break;
        for (int p = 0; p < 2; ++p) {
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0.0) continue;
                const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                const double t = (theta >= 0 ? 1.0 : -1.0) /
                                 (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; ++k) {  // A <- A J
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {  // A <- J^T A
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; ++k) {  // V <- V J
                    const double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    for (int i = 0; i < 3; ++i) w[i] = a[i][i];
}

}  // namespace

SnapStats snapFeatures(Mesh& mesh, const TriDexelStock& stock, const SnapOptions& options) {
    const Lattice& lat = stock.lattice();
    const double h = lat.h;
    const double singular = std::pow(std::tan(0.5 * options.featureAngle), 2.0);

    // The cell (i, j, k) of a vertex: the cube between lattice points i..i+1 etc.
    auto cellOf = [&](const Vec3& v, int c[3]) {
        for (int a = 0; a < 3; ++a) c[a] = int(std::floor((v[a] - lat.origin[a]) / h - 0.5));
    };
    auto keyOf = [](const int c[3]) {
        return (std::int64_t(c[0] + (1 << 20)) << 42) | (std::int64_t(c[1] + (1 << 20)) << 21) |
               std::int64_t(c[2] + (1 << 20));
    };
    std::unordered_map<std::int64_t, int> perCell;
    perCell.reserve(mesh.vertices.size());
    for (const Vec3& v : mesh.vertices) {
        int c[3];
        cellOf(v, c);
        ++perCell[keyOf(c)];
    }

    std::atomic<std::size_t> planes{0}, edges{0}, corners{0}, kept{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.vertices.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<Crossing> xs;
        std::size_t nPlane = 0, nEdge = 0, nCorner = 0, nKept = 0;
        for (std::size_t vi = r.begin(); vi < r.end(); ++vi) {
            Vec3& vertex = mesh.vertices[vi];
            int cell[3];
            cellOf(vertex, cell);
            if (perCell.at(keyOf(cell)) != 1) {
                ++nKept;
                continue;
            }
            // The exact crossings on the cell's twelve edges.
            xs.clear();
            for (int a = 0; a < 3; ++a) {
                const Axis axis = axisFromIndex(a);
                if (!stock.has(axis)) continue;
                const DexelFamily& fam = stock.family(axis);
                const int b = (a + 1) % 3, c = (a + 2) % 3;
                const double t0 = (cell[a] + 0.5) * h, t1 = t0 + h;
                for (int db = 0; db < 2; ++db) {
                    for (int dc = 0; dc < 2; ++dc) {
                        const int ib = cell[b] + db, ic = cell[c] + dc;
                        if (ib < 0 || ic < 0 || ib >= fam.nb() || ic >= fam.nc()) continue;
                        for (const Segment& s : fam.segments(ib, ic)) {
                            for (int end = 0; end < 2; ++end) {
                                const double e = end == 0 ? s.lo : s.hi;
                                if (e < t0 || e > t1) continue;
                                Crossing x;
                                x.p[a] = lat.origin[a] + e;
                                x.p[b] = lat.coord(axisFromIndex(b), ib);
                                x.p[c] = lat.coord(axisFromIndex(c), ic);
                                const double reach = kNeighbourReach * h;
                                const double sb = enoSlope(
                                    nearestEndpoint(fam, ib - 1, ic, end == 0, e, reach), e,
                                    nearestEndpoint(fam, ib + 1, ic, end == 0, e, reach), h);
                                const double sc = enoSlope(
                                    nearestEndpoint(fam, ib, ic - 1, end == 0, e, reach), e,
                                    nearestEndpoint(fam, ib, ic + 1, end == 0, e, reach), h);
                                x.n = Vec3(0.0);
                                if (!std::isnan(sb) && !std::isnan(sc)) {
                                    // Surface t = e(b, c): gradient of t - e is (1, -e_b, -e_c);
                                    // outward is -a at a segment's start, +a at its end.
                                    x.n[a] = 1.0;
                                    x.n[b] = -sb;
                                    x.n[c] = -sc;
                                    x.n = glm::normalize(x.n) * (end == 0 ? -1.0 : 1.0);
                                }
                                xs.push_back(x);
                            }
                        }
                    }
                }
            }
            if (xs.empty()) {
                ++nKept;
                continue;
            }
            // QEF about the mass point m: minimise |A (x - m) - (b - A m)|.
            Vec3 m(0.0);
            for (const Crossing& x : xs) m += x.p;
            m /= double(xs.size());
            double A[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
            Vec3 rhs(0.0);
            for (const Crossing& x : xs) {
                const double d = glm::dot(x.n, x.p - m);
                for (int i = 0; i < 3; ++i) {
                    for (int j = 0; j < 3; ++j) A[i][j] += x.n[i] * x.n[j];
                    rhs[i] += x.n[i] * d;
                }
            }
            double w[3], V[3][3];
            symmetricEigen(A, w, V);
            const double wmax = std::max({w[0], w[1], w[2]});
            Vec3 sol = m;
            int rank = 0;
            if (wmax > 0.0) {
                for (int k = 0; k < 3; ++k) {
                    if (w[k] <= singular * wmax) continue;
                    ++rank;
                    const Vec3 vk(V[0][k], V[1][k], V[2][k]);
                    sol += vk * (glm::dot(vk, rhs) / w[k]);
                }
            }
            // Accept only a point near the vertex's cell.
            bool ok = rank > 0;
            for (int a = 0; a < 3 && ok; ++a) {
                const double lo = lat.origin[a] + (cell[a] + 0.5) * h;
                ok = sol[a] >= lo - options.maxOutside * h && sol[a] <= lo + h + options.maxOutside * h;
            }
            if (!ok) {
                ++nKept;
                continue;
            }
            vertex = sol;
            (rank == 1 ? nPlane : rank == 2 ? nEdge : nCorner)++;
        }
        planes += nPlane;
        edges += nEdge;
        corners += nCorner;
        kept += nKept;
    });
    return {planes.load(), edges.load(), corners.load(), kept.load()};
}

}  // namespace dexelmill
