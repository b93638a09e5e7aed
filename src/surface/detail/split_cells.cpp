#include "surface/detail/split_cells.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "dexelmill/stock/fine_features.h"
#include "surface/detail/cell_loops.h"
#include "surface/detail/cell_table.h"
#include "surface/detail/crossings.h"
#include "surface/detail/patch_vertex.h"

namespace dexelmill::detail {

namespace {

using EdgeKey = std::pair<GridPoint, int>;

/// A stretch whose two ends have normals this close to square to the dexel (below this cosine
/// with it, 14.5 degrees) is where the surface grazes the dexel: the cap of a rounded surface
/// just past a lattice edge or face, a fraction of the stretch's length deep (on a sphere of
/// radius R a stretch of length L is L^2 / 8R deep and its ends' normals make a cosine of L / 2R
/// with the dexel). Its cells' loops would lie in a lattice face and stand their triangles on
/// edge. The family across such a feature sees it with normals along its dexels: of three
/// families one makes a cosine of at least 1/sqrt(3) with any normal.
constexpr double kGrazing = 0.25;

/// An end of a dexel's segment: its offset along the dexel (mm from the lattice origin) and
/// the material's outward normal there.
struct End {
    double t;
    PackedNormal n;
};

/// Whether the dexel holds the point at v, ends included (as TriDexelStock::inside).
bool holds(const SegmentSpan& segs, float v) {
    const Segment* s = std::partition_point(segs.begin(), segs.end(), [v](const Segment& g) { return g.hi < v; });
    return s != segs.end() && s->lo <= v;
}

/// The lattice edge a stretch lies on: the index i along its dexel with points i and i + 1 at
/// or beyond its ends; -1 when it lies outside the lattice's first or last point.
int edgeOfStretch(const FineStretch& s, double h, int n) {
    const int i = int(std::floor(double(s.lo) / h - 0.5));
    for (int k = std::max(0, i - 1); k <= i + 1 && k + 1 < n; ++k)
        if (float((k + 0.5) * h) <= s.lo && s.hi <= float((k + 1.5) * h)) return k;
    return -1;
}

/// How far from a thin stretch's middle keepOffFinMiddle keeps a patch's vertex, as a share of its
/// end's distance from it. Not none: a vertex on the middle could meet the other side's there. Not
/// more: where the fin thins away from the end (a wedge), a vertex on its own wall is nearer the
/// middle than the end is, and at a half it was moved off its wall (botomata_bottom: 104 vertices
/// by up to 0.017 h; at a quarter none).
constexpr double kOwnSide = 0.25;

/// A loop's crossing or face vertex this close (in h) to a face of its cell lies on it
/// (keepOffPathFaces): one off a face lies at least 1e-3 h from it (crossings are kept kCornerGap
/// from the lattice points, face vertices kFaceVertexGap from their face's edges); half that is
/// far above the rounding of lattice coordinates.
constexpr double kOnFace = 0.5e-3;

}  // namespace

/// A patch's vertex is where its crossings' tangent planes meet best (patch_vertex.cpp). Where the
/// surface is concave seen from the material, as a machined surface is but where cuts meet, those
/// planes meet beyond it, in the material: on a wall of radius R whose crossings span a cell, by
/// about h^2 / (8 R) (0.008 h where two plunges of radius 15 h leave a fin). On a fin thinner than
/// twice that, meshed from its dexels, the two sides' vertices passed each other and their fans
/// passed through one another (16 pairs of triangles at the neck of fins 0.006 to 0.02 h thick).
///
/// The stretch of material between an end p of the loop and the end q across it on the same edge
/// is exact. Where its ends' normals are within the feature angle of opposite (a fin whose sides
/// run alike), its midpoint m and the bisector n of those normals (n_p - n_q, normalised) stand
/// for the fin's middle there. Past that angle (a wedge) a plane through the stretch does not
/// follow the middle: in helical-thread-milling.gcode at h = 0.1 mm, where a plunge's wall meets
/// the helix's sloping flank 54 to 62 degrees from opposite, it moved vertices of a mesh with no
/// crossing pairs by up to 0.15 h.
///
/// Where the vertex v is short of n . (v - m) >= kOwnSide n . (p - m), it is moved along n until
/// it is not: it stays on p's side of the middle, and the other side's vertex, whose n is -n, on
/// q's, the two at least kOwnSide n . (p - q) apart along n. A vertex moves only by as much as it
/// stood past that. A loop that holds both p and q (the fin's end wrapping round, at its top or
/// bottom) meshes both sides and is left alone.
///
/// The plane through m across n stands for the fin's middle near its edge only: across the cell,
/// where the fin curves away from it, the move took vertices up to 0.1 h out of their cells, and
/// their fans through the fans of the cells beyond (boat-xyzac.ngc at h = 0.25 mm: 0.099 h below
/// the cell at (-3.71, 14.82, -5.54), a crease's vertex fitted onto the cell's floor, which its
/// loop meets; 15 of the 35 cells where the boat's triangles still crossed). The vertex is then
/// brought back within the box it was fitted in, its cell (lo to hi): a fan within its cell meets
/// another cell's only on their common face.
Vec3 keepOffFinMiddle(const SplitCells& cells, std::uint32_t k, double featureAngle, const Vec3& lo, const Vec3& hi,
                      Vec3 v) {
    const double cosFeature = std::cos(featureAngle);
    const auto begin = cells.loopIds.begin() + std::ptrdiff_t(cells.loopStart[k]);
    const auto end = cells.loopIds.begin() + std::ptrdiff_t(cells.loopStart[k + 1]);
    for (auto it = begin; it != end; ++it) {
        const std::uint32_t p = *it;
        if (p & SplitCells::kOrdinary || p >= cells.edgeEnds) continue;
        const std::uint32_t q = cells.partner[p];
        if (q == SplitCells::kNoPartner || std::find(begin, end, q) != end) continue;
        const PackedNormal np = cells.normals[p], nq = cells.normals[q];
        if (!np.present() || np.sharp() || !nq.present() || nq.sharp()) continue;
        const Vec3 side = np.unpack(), other = nq.unpack();
        if (glm::dot(side, other) > -cosFeature) continue;  // a wedge, not a fin
        const Vec3 n = glm::normalize(side - other);
        const Vec3 m = 0.5 * (cells.points[p] + cells.points[q]);
        const double shortBy = kOwnSide * glm::dot(n, cells.points[p] - m) - glm::dot(n, v - m);
        if (shortBy > 0.0) v += shortBy * n;
    }
    return glm::clamp(v, lo, hi);
}

/// A smooth patch's vertex (rank 0 or 1) keeps its whole cell, or the box of its crossings where
/// it shares the cell (PatchVertexRule::place), and either may put it on a face its loop crosses:
/// on a thin fin slanting across that face its crossings there bound the box, and the
/// least-squares point may lie past them (a wall concave seen from the fin puts it in the fin).
/// Its fan over its paths across that face then lies in the face. Over a lens it overlaps itself
/// if the lens rises past the vertex, and meets the fan of the cell across the face. (Two ball
/// plunges of radius 15 h whose walls pass 0.017 h apart, the fin slanting through the lattice
/// plane z = 1.5 at (9.62, 9.46): the vertex, clamped onto that face, sat 0.004 h outside a lens
/// 0.5 h deep; three pairs of triangles met.) Over a path between two edges it covers the face
/// round that path, where the cell across the face has its own fan over the same path, or over
/// another path of the face, and their triangles meet: the cell across stands its fan on the
/// face along the path's chord, which passes through the triangle lying in the face, or puts its
/// vertex on the face as well, the two fans then overlapping in it. (Two ball plunges of radius
/// 2 h whose walls pass 0.024 h apart at (9.53, 9.07, 1.92), the fin nearly in the lattice plane
/// x = 9.5: the face rule gave the split cell beyond it a patch holding crossings of both sides,
/// fitted past that face and clamped onto it at (9.5, 8.932, 1.999), where the table path's
/// vertex of the cell before it was clamped too, at (9.5, 8.903, 1.941); three pairs met. In 5 of
/// 3,000 such pairs of plunges a split cell's vertex stood on such a face.) Kept kFaceInset h off
/// every face that a path of its loop crosses, as a crease's or corner's vertex is off every
/// face, its fan leaves the face along the paths' chords, and two fan triangles that share an
/// edge meet only along it.
Vec3 keepOffPathFaces(const PatchVertexRule::Loop& loop, const Vec3& cellLo, double h, Vec3 v) {
    const double inset = PatchVertexRule::kFaceInset * h, near = kOnFace * h;
    for (int i = 0; i < loop.len; ++i) {
        const Vec3& p = loop.points[loop.index[i]];
        const Vec3& q = loop.points[loop.index[i + 1 == loop.len ? 0 : i + 1]];
        for (int a = 0; a < 3; ++a) {
            const double low = cellLo[a], high = cellLo[a] + h;
            if (std::abs(p[a] - low) < near && std::abs(q[a] - low) < near) v[a] = std::max(v[a], low + inset);
            if (std::abs(p[a] - high) < near && std::abs(q[a] - high) < near) v[a] = std::min(v[a], high - inset);
        }
    }
    return v;
}

SplitCells findSplitCells(const TriDexelStock& stock, const SplitInputs& in) {
    SplitCells out;
    const Lattice& lattice = stock.lattice();
    const double h = lattice.h, gap = in.cornerGap * h, thinnest = in.minStretch * h;
    const auto toGrid = [&](const GridPoint& l) { return GridPoint{l[0] + in.offset[0], l[1] + in.offset[1], l[2] + in.offset[2]}; };
    const auto world = [&](const GridPoint& g) {
        return lattice.point(g[0] - in.offset[0], g[1] - in.offset[1], g[2] - in.offset[2]);
    };
    const auto insideAt = [&](const GridPoint& g) { return in.value(g) < 0.0f; };

    // The candidate edges: those a stretch no lattice point lies in falls on.
    std::vector<FineStretch> material, gaps;
    findFineStretches(stock, material, gaps);
    std::vector<std::tuple<int, int, int, int>> candidates;  // axis, ib, ic, index along the dexel
    for (const auto* list : {&material, &gaps})
        for (const FineStretch& s : *list) {
            const int i = edgeOfStretch(s, h, lattice.n[std::size_t(s.family)]);
            if (i >= 0) candidates.emplace_back(s.family, s.ib, s.ic, i);
        }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());

    // Each candidate's ends strictly between its points; kept when it has two or more after
    // thin stretches are dropped, and it agrees with the level set at both points.
    struct SplitEdge {
        EdgeKey key;
        std::uint32_t first;
        std::vector<double> at;
        std::vector<Vec3> normals;  ///< zero where unknown or sharp
    };
    std::vector<SplitEdge> split;
    for (const auto& [a, ib, ic, i] : candidates) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        const SegmentSpan segs = stock.family(axisFromIndex(a)).segments(ib, ic);
        const float v0 = float((i + 0.5) * h), v1 = float((i + 1.5) * h);
        std::vector<End> ends;
        for (const Segment* s = std::partition_point(segs.begin(), segs.end(), [v0](const Segment& g) { return g.hi <= v0; });
             s != segs.end() && s->lo < v1; ++s) {
            if (v0 < s->lo) ends.push_back({double(s->lo), s->nlo});
            if (s->hi < v1) ends.push_back({double(s->hi), s->nhi});
        }
        const bool in0 = holds(segs, v0), in1 = holds(segs, v1);
        GridPoint lo{}, hi{};
        lo[std::size_t(a)] = i, lo[std::size_t(b)] = ib, lo[std::size_t(c)] = ic;
        lo = toGrid(lo);
        if (in.excluded && std::binary_search(in.excluded->begin(), in.excluded->end(), EdgeKey{lo, a})) continue;
        hi = lo;
        ++hi[std::size_t(a)];
        if (in1 != (in0 != (ends.size() % 2 == 1)) || insideAt(lo) != in0 || insideAt(hi) != in1) continue;
        // Away from the lattice points, as the contourer keeps its crossings; two ends closer
        // than minStretch leave a stretch too thin to mesh, and two where the surface grazes the
        // dexel a shallow one, each dropped with both its ends.
        const double t0 = (i + 0.5) * h, t1 = t0 + h;
        for (End& e : ends) e.t = std::clamp(e.t, t0 + gap, t1 - gap);
        const int along = a;
        const auto grazes = [along](const End& e) {
            return e.n.present() && !e.n.sharp() && std::abs(e.n.unpack()[along]) < kGrazing;
        };
        for (std::size_t k = 0; k + 1 < ends.size();) {
            if (ends[k + 1].t - ends[k].t < thinnest || (grazes(ends[k]) && grazes(ends[k + 1]))) {
                ends.erase(ends.begin() + std::ptrdiff_t(k), ends.begin() + std::ptrdiff_t(k + 2));
                k = k > 0 ? k - 1 : 0;
            } else {
                ++k;
            }
        }
        if (ends.size() < 2) continue;
        SplitEdge e{{lo, a}, std::uint32_t(out.points.size()), {}, {}};
        for (std::size_t k = 0; k < ends.size(); ++k) {
            // Material lies below the even ends where the edge starts in it, above them where not.
            const bool below = in0 == (k % 2 == 0);
            const bool bounded = below ? k > 0 : k + 1 < ends.size();
            out.partner.push_back(bounded ? e.first + std::uint32_t(below ? k - 1 : k + 1) : SplitCells::kNoPartner);
        }
        for (const End& end : ends) {
            Vec3 p = world(lo);
            p[a] = lattice.origin[a] + end.t;
            out.points.push_back(p);
            out.normals.push_back(end.n);
            e.at.push_back((end.t - t0) / h);
            e.normals.push_back(end.n.present() && !end.n.sharp() ? end.n.unpack() : Vec3(0.0));
        }
        split.push_back(std::move(e));
    }
    out.edgeEnds = out.points.size();
    std::sort(split.begin(), split.end(), [](const SplitEdge& x, const SplitEdge& y) { return x.key < y.key; });
    for (const SplitEdge& e : split) out.edges.push_back(e.key);

    // The cells round them (also those past the lattice's last points, which the level set's
    // band reaches: their crossings on these edges are these).
    for (const SplitEdge& e : split) {
        const int a = e.key.second, b = (a + 1) % 3, c = (a + 2) % 3;
        for (int d = 0; d < 4; ++d) {
            GridPoint cell = e.key.first;
            cell[std::size_t(b)] -= d & 1;
            cell[std::size_t(c)] -= d >> 1;
            out.cells.push_back(cell);
        }
    }
    std::sort(out.cells.begin(), out.cells.end());
    out.cells.erase(std::unique(out.cells.begin(), out.cells.end()), out.cells.end());

    // Their loops.
    std::map<EdgeKey, std::uint32_t> ordinary;
    std::map<std::tuple<GridPoint, int, std::uint32_t, std::uint32_t>, std::uint32_t> faceVertices;
    for (const GridPoint& cell : out.cells) {
        CellCrossings cc;
        cc.creaseCosine = std::cos(in.featureAngle);
        float f[kCellCorners];
        for (int k = 0; k < kCellCorners; ++k) {
            f[k] = in.value({cell[0] + (k & 1), cell[1] + ((k >> 1) & 1), cell[2] + ((k >> 2) & 1)});
            if (f[k] < 0.0f) cc.inside |= std::uint8_t(1u << k);
        }
        for (int face = 0; face < kCellFaces; ++face) {
            const std::array<int, 4> k = faceCorners(face);
            if (insideJoinedAcrossFace(f[k[0]], f[k[1]], f[k[2]], f[k[3]])) cc.joined |= std::uint8_t(1u << face);
        }
        for (int e = 0; e < kCellEdges; ++e) {
            const int c0 = edgeCorner(e, 0), a = edgeAxis(e);
            const EdgeKey key{{cell[0] + (c0 & 1), cell[1] + ((c0 >> 1) & 1), cell[2] + ((c0 >> 2) & 1)}, a};
            EdgeCrossings& x = cc.edges[std::size_t(e)];
            const auto s = std::lower_bound(split.begin(), split.end(), key,
                                            [](const SplitEdge& se, const EdgeKey& k) { return se.key < k; });
            if (s != split.end() && s->key == key) {
                for (std::size_t j = 0; j < s->at.size(); ++j) x.ids.push_back(s->first + std::uint32_t(j));
                x.at = s->at;
                x.normals = s->normals;
                continue;
            }
            const bool lowerIn = (cc.inside >> c0) & 1;
            if (lowerIn == bool((cc.inside >> edgeCorner(e, 1)) & 1)) continue;
            auto o = ordinary.find(key);
            if (o == ordinary.end()) {
                o = ordinary.emplace(key, std::uint32_t(out.ordinary.size()) | SplitCells::kOrdinary).first;
                out.ordinary.push_back(key);
            }
            const auto [at, normal] = in.crossing(key.first, a, lowerIn);
            x.ids.push_back(o->second);
            x.at.push_back(at);
            x.normals.push_back(normal);
        }
        const auto faceVertex = [&](int face, std::uint32_t from, std::uint32_t to, double u, double v) {
            const int a = face >> 1;
            GridPoint lo = cell;
            lo[std::size_t(a)] += face & 1;
            const auto key = std::make_tuple(lo, a, std::min(from, to), std::max(from, to));
            auto it = faceVertices.find(key);
            if (it == faceVertices.end()) {
                Vec3 p = world(lo);
                p[(a + 1) % 3] += u * h;
                p[(a + 2) % 3] += v * h;
                it = faceVertices.emplace(key, std::uint32_t(out.points.size())).first;
                out.points.push_back(p);
                out.normals.push_back(PackedNormal{});
                out.faceVertexEnds.push_back({from, to});
            }
            return it->second;
        };
        for (const auto& loop : cellLoops(cc, faceVertex)) {
            out.loopIds.insert(out.loopIds.end(), loop.begin(), loop.end());
            out.loopStart.push_back(std::uint32_t(out.loopIds.size()));
            out.patchCell.push_back(cell);
        }
        out.cellPatchStart.push_back(std::uint32_t(out.patchCell.size()));
    }
    return out;
}

// Each patch's vertex is placed from its own loop alone, kept off the others' only by the middle
// of a fin's stretch at its edge (keepOffFinMiddle), and two vertices can still change places
// across the cell. In boat-xyzac.ngc at h = 0.25 mm (cells at (-9.13, 12.80, -4.03) and (34.97,
// -13.15, -5.52), 11 pairs) a fin 0.02 to 0.035 h thick leans over a floor; its sides' normals at
// the edge are 14 degrees from opposite, their tangent planes cross 0.17 h along the cell's face
// (in the first), and the crease where the upper side meets the floor was fitted 0.018 h under the
// lower side, in the air below the fin that the other patch bounds. A fold would go unseen there:
// each fan is whole and faces its way. A cell holds at most four patches of a few triangles each,
// so every pair is tested.
std::vector<std::uint32_t> crossingPatchTriangles(const SplitCells& cells, const Mesh& mesh,
                                                  const std::vector<std::uint32_t>& firstTriangle, double tol) {
    std::vector<std::uint32_t> out;
    const auto size = [&](std::uint32_t k) {
        return int(cells.loopStart[k + 1] - cells.loopStart[k]);
    };
    for (std::size_t c = 0; c < cells.cells.size(); ++c)
        for (std::uint32_t k = cells.cellPatchStart[c]; k < cells.cellPatchStart[c + 1]; ++k)
            for (std::uint32_t l = k + 1; l < cells.cellPatchStart[c + 1]; ++l) {
                const std::uint32_t k0 = firstTriangle[k], l0 = firstTriangle[l];
                for (const auto& [i, j] :
                     fanCrossings(mesh.triangles.data() + k0, size(k), mesh.triangles.data() + l0,
                                  size(l), mesh.vertices.data(), tol))
                    out.insert(out.end(), {k0 + std::uint32_t(i), l0 + std::uint32_t(j)});
            }
    return out;
}

}  // namespace dexelmill::detail
