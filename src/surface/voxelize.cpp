// Casting a closed triangle mesh into tri-dexels (no OpenVDB here).
#include "dexelmill/surface/voxelize.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "dexelmill/error.h"
#include "memory/pages.h"
#include "surface/detail/tile_fill.h"

namespace dexelmill {

namespace {

struct P2 {
    double x, y;
};

/// orient2d(a, b, q) evaluated in one canonical order of {a, b}, so that the two triangles
/// sharing an edge get exactly opposite values at every q (and both exactly 0 on the edge).
inline double edgeFunction(const P2& a, const P2& b, const P2& q) {
    const bool ordered = a.x < b.x || (a.x == b.x && a.y < b.y);
    const P2& p = ordered ? a : b;
    const P2& r = ordered ? b : a;
    const double v = (r.x - p.x) * (q.y - p.y) - (r.y - p.y) * (q.x - p.x);
    return ordered ? v : -v;
}

/// Top-left rule: which of the two triangles sharing an edge owns a point exactly on it. True
/// for exactly one of the directions a->b and b->a.
inline bool ownsEdge(const P2& from, const P2& to) {
    const double dx = to.x - from.x, dy = to.y - from.y;
    return dy > 0.0 || (dy == 0.0 && dx < 0.0);
}

struct Hit {
    double t;
    int dir;  // +1 entering material along the line, -1 leaving
    std::uint32_t triangle;
};

/// The outward unit normal of triangle t, turned if need be to point against the line (axis a)
/// where the line enters the material and along it where it leaves: the triangles of a mesh that
/// is not consistently oriented can face either way.
PackedNormal hitNormal(const Mesh& mesh, const Hit& hit, int a, bool entering) {
    Vec3 n = mesh.areaVector(hit.triangle);
    if ((n[a] > 0.0) == entering) n = -n;
    return PackedNormal::pack(n);
}

/// The segments of one dexel from its crossings; false when the winding did not return to 0.
bool hitsToSegments(const Mesh& mesh, std::vector<Hit>& hits, double len, int a, std::vector<Segment>& segs) {
    std::sort(hits.begin(), hits.end(), [](const Hit& p, const Hit& q) {
        return p.t < q.t || (p.t == q.t && p.dir < q.dir);
    });
    const Axis axis = axisFromIndex(a);
    int winding = 0;
    const Hit* start = nullptr;
    for (const Hit& hit : hits) {
        const int before = winding;
        winding += hit.dir;
        if (before == 0 && winding != 0) start = &hit;
        if (before != 0 && winding == 0)
            detail::appendSegment(segs, start->t, hit.t, len, axis, hitNormal(mesh, *start, a, true),
                                  hitNormal(mesh, hit, a, false));
    }
    if (winding == 0) return true;
    // Fall back to parity of the sorted crossings.
    segs.clear();
    for (std::size_t i = 0; i + 1 < hits.size(); i += 2)
        detail::appendSegment(segs, hits[i].t, hits[i + 1].t, len, axis, hitNormal(mesh, hits[i], a, true),
                              hitNormal(mesh, hits[i + 1], a, false));
    return false;
}

}  // namespace

MeshCastStats castMesh(const Mesh& mesh, TriDexelStock& stock) {
    for (const Mesh::Triangle& t : mesh.triangles)
        for (std::uint32_t i : t)
            if (i >= mesh.vertices.size()) throw Error("mesh has a vertex index past its vertex list");
    const Lattice& lat = stock.lattice();
    constexpr int kTile = DexelTile::kTile;
    std::atomic<std::size_t> hitCount{0}, unpaired{0};

    // Each triangle's dexel index box across the family, and the triangles by tile row: made
    // once for the three families, so that their pages are faulted in once (on a virtual machine
    // the faults of three fresh lists cost as much as the cast's own work on bear's design).
    struct Span {
        int b0, b1, c0, c1;
    };
    std::vector<Span, NoZeroAllocator<Span>> spans;
    detail::reservePopulated(spans, mesh.triangles.size());
    spans.resize(mesh.triangles.size());
    std::vector<std::uint32_t, NoZeroAllocator<std::uint32_t>> bucket;
    for (int a = 0; a < 3; ++a) {
        const Axis axis = axisFromIndex(a);
        if (!stock.has(axis)) continue;
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        const Axis axisB = axisFromIndex(b), axisC = axisFromIndex(c);
        DexelFamily& fam = stock.family(axis);
        const double len = lat.n[a] * lat.h;

        tbb::parallel_for(std::size_t(0), mesh.triangles.size(), [&](std::size_t t) {
            Box box;
            for (std::uint32_t i : mesh.triangles[t]) box.expand(mesh.vertices[i]);
            const auto rb = lat.indexRange(axisB, box.lo[b], box.hi[b]);
            const auto rc = lat.indexRange(axisC, box.lo[c], box.hi[c]);
            spans[t] = {rb[0], rb[1], rc[0], rc[1]};
        });
        std::vector<std::size_t> rowStart(std::size_t(fam.tilesC()) + 1, 0);
        for (const Span& s : spans) {
            if (s.b0 > s.b1 || s.c0 > s.c1) continue;
            for (int tc = s.c0 / kTile; tc <= s.c1 / kTile; ++tc) ++rowStart[std::size_t(tc) + 1];
        }
        for (std::size_t r = 1; r < rowStart.size(); ++r) rowStart[r] += rowStart[r - 1];
        if (bucket.capacity() < rowStart.back()) {
            bucket = {};
            detail::reservePopulated(bucket, rowStart.back());
        }
        bucket.resize(rowStart.back());
        {
            std::vector<std::size_t> fillAt(rowStart.begin(), rowStart.end() - 1);
            for (std::size_t t = 0; t < spans.size(); ++t) {
                const Span& s = spans[t];
                if (s.b0 > s.b1 || s.c0 > s.c1) continue;
                for (int tc = s.c0 / kTile; tc <= s.c1 / kTile; ++tc)
                    bucket[fillAt[std::size_t(tc)]++] = std::uint32_t(t);
            }
        }

        tbb::parallel_for(0, fam.tilesC(), [&](int tc) {
            detail::TileRowSegments row(tc, fam.nb());
            std::vector<std::vector<Hit>> hits(row.dexels.size());
            const int icLo = tc * kTile, icHi = std::min(fam.nc(), icLo + kTile) - 1;
            std::size_t found = 0, bad = 0;
            for (std::size_t k = rowStart[std::size_t(tc)]; k < rowStart[std::size_t(tc) + 1]; ++k) {
                const std::size_t t = bucket[k];
                const Mesh::Triangle& tri = mesh.triangles[t];
                const Vec3* v[3] = {&mesh.vertices[tri[0]], &mesh.vertices[tri[1]],
                                    &mesh.vertices[tri[2]]};
                const P2 p[3] = {{(*v[0])[b], (*v[0])[c]}, {(*v[1])[b], (*v[1])[c]},
                                 {(*v[2])[b], (*v[2])[c]}};
                const Span& s = spans[t];
                for (int ic = std::max(s.c0, icLo); ic <= std::min(s.c1, icHi); ++ic) {
                    for (int ib = s.b0; ib <= s.b1; ++ib) {
                        const P2 q{lat.coord(axisB, ib), lat.coord(axisC, ic)};
                        // w[i]: weight of vertex i, the edge function of the opposite edge.
                        const double w[3] = {edgeFunction(p[1], p[2], q), edgeFunction(p[2], p[0], q),
                                             edgeFunction(p[0], p[1], q)};
                        const bool anyPos = w[0] > 0 || w[1] > 0 || w[2] > 0;
                        const bool anyNeg = w[0] < 0 || w[1] < 0 || w[2] < 0;
                        if (anyPos == anyNeg) continue;  // outside, or edge-on
                        const int sigma = anyPos ? 1 : -1;
                        bool inside = true;
                        for (int i = 0; i < 3 && inside; ++i) {
                            if (w[i] != 0.0) continue;
                            // The edge opposite vertex i, in counter-clockwise order.
                            const P2& from = p[(i + (sigma > 0 ? 1 : 2)) % 3];
                            const P2& to = p[(i + (sigma > 0 ? 2 : 1)) % 3];
                            inside = ownsEdge(from, to);
                        }
                        if (!inside) continue;
                        const double sum = w[0] + w[1] + w[2];
                        const double t3 =
                            (w[0] * (*v[0])[a] + w[1] * (*v[1])[a] + w[2] * (*v[2])[a]) / sum;
                        // Counter-clockwise across the line means the normal points along +a:
                        // the line leaves the solid there.
                        hits[std::size_t(ic - icLo) * fam.nb() + ib].push_back(
                            {t3 - lat.origin[a], -sigma, std::uint32_t(t)});
                        ++found;
                    }
                }
            }
            for (int ic = icLo; ic <= icHi; ++ic) {
                for (int ib = 0; ib < fam.nb(); ++ib) {
                    std::vector<Hit>& h = hits[std::size_t(ic - icLo) * fam.nb() + ib];
                    if (h.empty()) continue;
                    if (!hitsToSegments(mesh, h, len, a, row.at(ib, ic))) ++bad;
                }
            }
            detail::assignTileRow(fam, row);
            hitCount += found;
            unpaired += bad;
        });
    }
    return {hitCount.load(), unpaired.load()};
}

TriDexelStock stockFromMesh(const Mesh& mesh, const Lattice& lattice, FamilySet families,
                            MeshCastStats* stats) {
    TriDexelStock stock(lattice, families);
    const MeshCastStats s = castMesh(mesh, stock);
    if (stats) *stats = s;
    return stock;
}

}  // namespace dexelmill
