// Points spread over a mesh's triangles: each triangle sampled by a lattice of smaller copies of
// itself, or by rows along its longest edge where that needs fewer points (a sliver), at the finest
// spacing a point budget allows.
//
// The bound. Every point of a triangle whose edges are at most s long lies within s / sqrt(3) of
// one of its corners: within its circumradius when it is acute, which is at most s / sqrt(3) since
// its largest angle lies between 60 and 90 degrees; within half its longest edge otherwise (the
// triangle then lies in the disc whose diameter is that edge, and each of its points is nearer an
// end of that edge than the edge's half, or nearer the third corner).
//
// The lattice. A triangle whose longest edge is L is cut into k^2 copies of itself scaled by 1 / k,
// k = ceil(L / s): every copy's edges are at most s, so every point lies within s / sqrt(3) of a
// corner of its copy. Each copy gives a third of its area to each of its corners: a share lying
// within s of its point.
//
// The rows. Let AB be the longest edge, L long, and C the corner at height h over it. AB faces the
// largest angle, so the angles at A and B are at most 90 degrees (neither exceeds the angle at C,
// and the three add up to 180): the sides AC and BC lean inwards, and the chord of the triangle
// parallel to AB at any height, projected perpendicularly onto a lower chord, lies within it.
// Rows are the chords at heights y_j = j h / m (j = 0 .. m - 1; row 0 is AB), each with points
// evenly spaced at most t apart from one end to the other. A point X of the strip between y_j and
// y_j+1 lies at most a = h / m above row j, and its foot there lies in the row, within t / 2 of one
// of its points: X lies within sqrt(a^2 + t^2 / 4) of that point. With m = ceil(sqrt(2) h / r),
// a <= r / sqrt(2), and t = 2 sqrt(r^2 - a^2) >= sqrt(2) r, that is r = s / sqrt(3). Each point
// stands for the part of its strip whose foot on its row lies nearer it than the row's other
// points: a share within r of it. C is no row's point, and stands for none of the triangle.
//
// A point covers about s^2 / 3 of a row's strip (a t at a = r / sqrt(2)), and about 0.87 s^2 of the
// lattice's: a triangle near equilateral takes the lattice; a sliver, whose height is below about a
// third of its longest edge, the rows, whose points grow with L h / s^2 where the lattice's grow
// with L^2 / s^2.
#include "compare/detail/surface_samples.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

namespace dexelmill {

namespace {

/// The bisection of the spacing stops when its bracket [lo, hi] is this narrow (hi / lo): the
/// spacing returned (hi) meets the budget, and lo, less than 2 % finer, exceeds it. From the
/// finest spacing to the longest edge (at most sqrt(3) / 1e-4 apart in deviation.cpp) that takes
/// 9 passes over the triangles, after the one that tries the finest.
constexpr double kSpacingRatio = 1.02;

/// The spacing is never finer than this fraction of the longest edge: a triangle would then add
/// more than 5e11 points, beyond any budget a mesh of 2^32 vertices sets, and the counts of
/// points stay far below 2^64.
constexpr double kFinestOfLongest = 1e-6;

/// The corners of triangle t as A, B (its longest edge) and C.
struct Corners {
    std::uint32_t a, b, c;
};

Corners corners(const Mesh& mesh, std::size_t t) {
    const auto& v = mesh.triangles[t];
    const Vec3 &p = mesh.vertices[v[0]], &q = mesh.vertices[v[1]], &r = mesh.vertices[v[2]];
    const double e[3] = {glm::length(q - p), glm::length(r - q), glm::length(p - r)};
    const int k = e[0] >= e[1] && e[0] >= e[2] ? 0 : e[1] >= e[2] ? 1 : 2;
    return {v[std::size_t(k)], v[std::size_t((k + 1) % 3)], v[std::size_t((k + 2) % 3)]};
}

TriangleShape shape(const Mesh& mesh, const Corners& k) {
    const Vec3 &a = mesh.vertices[k.a], &b = mesh.vertices[k.b], &c = mesh.vertices[k.c];
    const double longest = glm::length(b - a);
    return {longest, longest > 0.0 ? glm::length(glm::cross(b - a, c - a)) / longest : 0.0};
}

/// The points a lattice of k pieces along each edge adds to the triangle's corners.
std::uint64_t latticeAdded(std::uint64_t k) { return (k + 1) * (k + 2) / 2 - 3; }

/// The pieces row j of `rows` is cut into, `q` the longest edge over rows x along: the row is
/// (rows - j) / rows of the longest edge.
std::uint64_t rowPieces(double q, std::uint64_t rows, std::uint64_t j) {
    return std::max<std::uint64_t>(1, std::uint64_t(std::ceil(q * double(rows - j))));
}

/// The area of the strip of the rows pattern between heights v0 h and v1 h whose foot on the
/// longest edge (AB on the x axis from 0 to `longest`, C above `apex`) lies at x or before. Across
/// the strip the width that does so, min(x, right(v)) - left(v) or 0, is linear but where x meets
/// a side: the trapezoid rule between those heights is exact.
double stripAreaBefore(double x, double longest, double apex, double height, double v0, double v1) {
    double cut[4] = {v0, v1, v0, v0};
    int n = 2;
    if (longest > apex) {
        const double v = (longest - x) / (longest - apex);  // x meets BC
        if (v > v0 && v < v1) cut[n++] = v;
    }
    if (apex > 0.0) {
        const double v = x / apex;  // x meets AC
        if (v > v0 && v < v1) cut[n++] = v;
    }
    std::sort(cut, cut + n);
    const auto width = [&](double v) { return std::max(0.0, std::min(x, longest + (apex - longest) * v) - apex * v); };
    double area = 0.0;
    for (int i = 0; i + 1 < n; ++i) area += 0.5 * (cut[i + 1] - cut[i]) * (width(cut[i]) + width(cut[i + 1]));
    return height * area;
}

/// The points all triangles add at `spacing`, or `cap` if more.
std::uint64_t addedPoints(const std::vector<TriangleShape>& shapes, double spacing, std::uint64_t cap) {
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, shapes.size()), std::uint64_t(0),
        [&](const tbb::blocked_range<std::size_t>& r, std::uint64_t sum) {
            for (std::size_t t = r.begin(); t != r.end() && sum < cap; ++t)
                sum = std::min(cap, sum + std::min(cap, trianglePattern(shapes[t], spacing).added));
            return sum;
        },
        // Capped sums of counts up to the cap: exact below it, whatever the order.
        [&](std::uint64_t a, std::uint64_t b) { return std::min(cap, a + b); });
}

}  // namespace

TrianglePattern trianglePattern(const TriangleShape& shape, double spacing) {
    const double L = shape.longest, h = shape.height;
    if (L <= spacing) return {};
    TrianglePattern lattice;
    lattice.pieces = std::uint64_t(std::ceil(L / spacing));
    lattice.added = latticeAdded(lattice.pieces);
    const double r = spacing / std::sqrt(3.0);
    const std::uint64_t m = std::max<std::uint64_t>(1, std::uint64_t(std::ceil(std::sqrt(2.0) * h / r)));
    const double a = h / double(m);
    const double t = 2.0 * r * std::sqrt(std::max(0.0, 1.0 - (a / r) * (a / r)));
    // Row j takes at least (L / t) (m - j) / m + 1 points, so the rows add at least
    // (L / t) (m + 1) / 2 + m - 2: where the lattice adds no more, they need not be counted.
    if (double(lattice.added) <= L / t * double(m + 1) / 2.0 + double(m) - 2.0) return lattice;
    const double q = L / (double(m) * t);
    std::uint64_t added = 0;
    for (std::uint64_t j = 0; j < m && added < lattice.added + 2; ++j) added += rowPieces(q, m, j) + 1;
    if (added < lattice.added + 2) return {0, m, t, added - 2};
    return lattice;
}

SurfaceSamples sampleSurface(const Mesh& mesh, double finest, std::uint64_t budget) {
    SurfaceSamples out;
    const std::size_t nt = mesh.triangles.size();
    out.vertexArea.assign(mesh.vertices.size(), 0.0);
    std::vector<Corners> ends(nt);
    std::vector<TriangleShape> shapes(nt);
    tbb::parallel_for(std::size_t(0), nt, [&](std::size_t t) {
        ends[t] = corners(mesh, t);
        shapes[t] = shape(mesh, ends[t]);
    });

    // The spacing: finest if it meets the budget; else bisected (on its logarithm) between finest,
    // which does not, and the longest edge, where every triangle is measured at its corners alone.
    double longest = 0.0;
    for (const TriangleShape& s : shapes) longest = std::max(longest, s.longest);
    double lo = std::max(finest, kFinestOfLongest * longest), hi = std::max(lo, longest);
    if (addedPoints(shapes, lo, budget + 1) <= budget) hi = lo;
    while (hi > kSpacingRatio * lo) {
        const double mid = std::sqrt(lo * hi);
        (addedPoints(shapes, mid, budget + 1) <= budget ? hi : lo) = mid;
    }
    out.spacing = hi;

    std::vector<TrianglePattern> patterns(nt);
    tbb::parallel_for(std::size_t(0), nt, [&](std::size_t t) { patterns[t] = trianglePattern(shapes[t], out.spacing); });
    std::vector<std::size_t> first(nt + 1, 0);
    for (std::size_t t = 0; t < nt; ++t) first[t + 1] = first[t] + std::size_t(patterns[t].added);
    out.points.resize(first[nt]);
    out.pointArea.resize(first[nt]);
    // The shares of each triangle's corners A, B, C, summed into the vertices' afterwards.
    std::vector<std::array<double, 3>> cornerArea(nt);
    tbb::parallel_for(std::size_t(0), nt, [&](std::size_t t) {
        const TrianglePattern& p = patterns[t];
        const Corners& k = ends[t];
        const Vec3 &A = mesh.vertices[k.a], &B = mesh.vertices[k.b], &C = mesh.vertices[k.c];
        const double L = shapes[t].longest, h = shapes[t].height;
        std::size_t at = first[t];
        if (p.rows == 0) {
            const std::uint64_t n = p.pieces;
            const double third = L * h / (6.0 * double(n) * double(n));
            cornerArea[t] = {third, third, third};
            for (std::uint64_t i = 0; i <= n; ++i)
                for (std::uint64_t j = 0; i + j <= n; ++j) {
                    const bool onEdge = i == 0 || j == 0 || i + j == n;
                    if (onEdge && (i == n || j == n || i + j == 0)) continue;  // a corner: a vertex
                    out.points[at] = A + (double(i) / double(n)) * (B - A) + (double(j) / double(n)) * (C - A);
                    out.pointArea[at++] = (onEdge ? 3.0 : 6.0) * third;
                }
            return;
        }
        // Rows: in the plane, A = (0, 0), B = (L, 0), C = (apex, h); a point's share is the part of
        // its strip whose foot lies between the midpoints to its neighbours on the row.
        const std::uint64_t m = p.rows;
        const double apex = L > 0.0 ? std::clamp(glm::dot(C - A, B - A) / L, 0.0, L) : 0.0;
        const double q = L / (double(m) * p.along);
        cornerArea[t] = {0.0, 0.0, 0.0};
        for (std::uint64_t j = 0; j < m; ++j) {
            const std::uint64_t n = rowPieces(q, m, j);
            const double v0 = double(j) / double(m), v1 = double(j + 1) / double(m);
            const Vec3 from = A + v0 * (C - A), to = B + v0 * (C - B);
            const double left = apex * v0, right = L + (apex - L) * v0;
            double before = 0.0;  // the strip's area whose foot lies before the current point's share
            for (std::uint64_t i = 0; i <= n; ++i) {
                const double end = i == n ? right : left + (right - left) * (double(i) + 0.5) / double(n);
                const double upTo = stripAreaBefore(end, L, apex, h, v0, v1);
                const double share = upTo - before;
                before = upTo;
                if (j == 0 && i == 0) cornerArea[t][0] = share;
                else if (j == 0 && i == n) cornerArea[t][1] = share;
                else {
                    out.points[at] = from + (double(i) / double(n)) * (to - from);
                    out.pointArea[at++] = share;
                }
            }
        }
    });
    for (std::size_t t = 0; t < nt; ++t) {
        out.vertexArea[ends[t].a] += cornerArea[t][0];
        out.vertexArea[ends[t].b] += cornerArea[t][1];
        out.vertexArea[ends[t].c] += cornerArea[t][2];
    }
    return out;
}

}  // namespace dexelmill
