#include "surface/detail/cell_loops.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>

#include <glm/geometric.hpp>

#include "surface/detail/cell_table.h"

namespace dexelmill::detail {

namespace {

/// A face vertex lies at least this far (in spacings) from the face's edges.
constexpr double kFaceVertexGap = 1e-3;
/// A face vertex lies at least this fraction of its lens's chord into the face: on a flatter lens
/// the fan triangles on its two sides, in the two cells sharing the face, would stand nearly flat
/// against each other and fold (the lens of a quarter of a circle rises 0.21 of its chord).
constexpr double kMinLensRise = 0.2;
/// A path across a face that goes round another on the same edge lies at least this much deeper.
constexpr double kNestedDepthStep = 1.0 / 16.0;
/// Samples along the line into the face on which a face vertex's depth is searched, and the
/// bisection steps after the first change of sign (to 2^-20 of a spacing).
constexpr int kDepthSamples = 32;
constexpr int kDepthBisections = 20;
/// Tangent lines in a face whose normals make a sine below this are taken as parallel.
constexpr double kParallelSine = 1e-6;
/// A normal whose part in the face is shorter than this gives no direction there.
constexpr double kInFace = 1e-3;
/// A sheet whose unit normal's part in the face is below this (it meets the face at less than 30
/// degrees) has no tangent line there that reaches a wedge's tip. Its slice through the face bends
/// by the sheet's normal curvature divided by that part (Meusnier), so near a ridge's highest
/// point, where the sheet lies nearly in the face, the slice is an island whose side curls round
/// at once. (Bear, the lattice plane z = -5.116 at (50.545, 22.56): a ridge's slice 0.26 mm long,
/// one end's normal 0.36 in the face; its tangent met the other's 0.114 mm in, near that end,
/// where the tip lies 0.055 mm in at the middle; the arc the normals turn by puts it 0.062 mm in.)
constexpr double kGrazingInFace = 0.5;
/// Halvings of a lens's depth tried at a time where its path crosses another path of the face.
constexpr int kUncrossHalvings = 24;
/// Evenly spaced sample lines of the face rule, per direction, besides those between crossings.
constexpr int kUniformLines = 8;
constexpr double kPi = 3.14159265358979323846;

/// A face in its own frame: across axis a at offset s of the cell, with in-face axes u = (a + 1) % 3
/// and v = (a + 2) % 3, which turn counter-clockwise about +a. Its corners and edges are listed in
/// the order of the walk round it: corners (0, 0), (1, 0), (1, 1), (0, 1) in (u, v); edges
/// E0 (v = 0, walked up u), E1 (u = 1, up v), E2 (v = 1, down u), E3 (u = 0, down v).
struct Frame {
    int a = 0, s = 0, u = 0, v = 0;
    std::array<int, 4> corner{}, edge{};
};

int edgeFromCorner(int k, int axis) {
    return 4 * axis + cornerOffset(k, (axis + 1) % 3) + 2 * cornerOffset(k, (axis + 2) % 3);
}

Frame frameOf(int face) {
    Frame f;
    f.a = face >> 1;
    f.s = face & 1;
    f.u = (f.a + 1) % 3;
    f.v = (f.a + 2) % 3;
    const auto corner = [&](int cu, int cv) { return (f.s << f.a) | (cu << f.u) | (cv << f.v); };
    f.corner = {corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)};
    f.edge = {edgeFromCorner(f.corner[0], f.u), edgeFromCorner(f.corner[1], f.v), edgeFromCorner(f.corner[3], f.u),
              edgeFromCorner(f.corner[0], f.v)};
    return f;
}

/// A crossing met on the walk: its id, the walk edge (0 to 3), its offset along that lattice edge
/// and its walk position (edge + fraction walked along it).
struct WalkCrossing {
    std::uint32_t id;
    int side;
    double at, walk;
    Vec3 normal;  ///< zero where unknown
};

/// One face's edges, with membership and the blend of cell_loops.h.
class FaceField {
public:
    FaceField(const CellCrossings& cell, const Frame& f) : cell_(cell), f_(f) {
        for (int i = 0; i < 4; ++i) {
            const EdgeCrossings& e = cell.edges[std::size_t(f.edge[std::size_t(i)])];
            if (e.at.size() < 2) continue;
            for (std::size_t k = 0; k < e.at.size(); ++k) {
                const double t = e.at[k];
                const std::array<double, 2> x = i == 0 ? std::array<double, 2>{t, 0.0}
                                                : i == 1 ? std::array<double, 2>{1.0, t}
                                                : i == 2 ? std::array<double, 2>{t, 1.0}
                                                         : std::array<double, 2>{0.0, t};
                std::array<double, 2> m{0.0, 0.0};
                if (k < e.normals.size()) {
                    const double a = e.normals[k][f.u], b = e.normals[k][f.v], l = std::hypot(a, b);
                    if (l > kInFace) m = {a / l, b / l};
                }
                tangents_.push_back({x, m});
            }
        }
    }

    /// Whether the point at offset s along walk edge i (from its lattice lower end) is in material.
    bool member(int i, double s) const {
        const int e = f_.edge[std::size_t(i)];
        bool in = (cell_.inside >> edgeCorner(e, 0)) & 1;
        for (double t : cell_.edges[std::size_t(e)].at)
            if (t < s) in = !in;
        return in;
    }

    /// The signed distance along walk edge i to its nearest crossing, at most 1, negative in material.
    double edgeValue(int i, double s) const {
        double d = 1.0;
        for (double t : cell_.edges[std::size_t(f_.edge[std::size_t(i)])].at) d = std::min(d, std::abs(s - t));
        return member(i, s) ? -d : d;
    }

    double cornerValue(int k) const { return (cell_.inside >> f_.corner[std::size_t(k)]) & 1 ? -1.0 : 1.0; }

    /// The field the face rule reads at (u, v), negative in material: where the nearest of the
    /// crossings on edges with several has a normal with a part in the face, the signed distance
    /// to its tangent line there (a thin wall or slot runs on along its sides' tangents, also past
    /// the middle of its stretch, or at a slant); elsewhere the Coons blend. Crossings on edges
    /// with one are left out: near the foot of a thin wall the floor's tangent would cut the wall
    /// off.
    double value(double u, double v) const {
        double best = std::numeric_limits<double>::infinity();
        const Tangent* nearest = nullptr;
        for (const Tangent& t : tangents_) {
            const double d = std::hypot(u - t.at[0], v - t.at[1]);
            if (d < best) best = d, nearest = &t;
        }
        if (nearest && (nearest->normal[0] != 0.0 || nearest->normal[1] != 0.0))
            return nearest->normal[0] * (u - nearest->at[0]) + nearest->normal[1] * (v - nearest->at[1]);
        return blend(u, v);
    }

    /// The Coons blend of the four edges at (u, v).
    double blend(double u, double v) const {
        const double edges = (1.0 - v) * edgeValue(0, u) + v * edgeValue(2, u) + (1.0 - u) * edgeValue(3, v) +
                             u * edgeValue(1, v);
        const double corners = (1.0 - u) * (1.0 - v) * cornerValue(0) + u * (1.0 - v) * cornerValue(1) +
                               u * v * cornerValue(2) + (1.0 - u) * v * cornerValue(3);
        return edges - corners;
    }

private:
    /// A crossing in the face's (u, v) and its unit normal in the face (zero when unknown).
    struct Tangent {
        std::array<double, 2> at, normal;
    };
    const CellCrossings& cell_;
    const Frame& f_;
    std::vector<Tangent> tangents_;
};

/// The sample lines across a face along one direction: its ends, the middles between consecutive
/// crossings of its two parallel edges taken together (so that a line runs between any two
/// crossings, on one edge or across), and kUniformLines more, evenly spaced; sorted and unique.
std::vector<double> sampleLines(const EdgeCrossings& e0, const EdgeCrossings& e1) {
    std::vector<double> breaks{0.0, 1.0};
    breaks.insert(breaks.end(), e0.at.begin(), e0.at.end());
    breaks.insert(breaks.end(), e1.at.begin(), e1.at.end());
    std::sort(breaks.begin(), breaks.end());
    std::vector<double> out{0.0, 1.0};
    for (std::size_t k = 0; k + 1 < breaks.size(); ++k)
        if (breaks[k + 1] > breaks[k]) out.push_back(0.5 * (breaks[k] + breaks[k + 1]));
    for (int k = 1; k < kUniformLines; ++k) out.push_back(double(k) / kUniformLines);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

int find(std::vector<int>& parent, int i) {
    while (parent[std::size_t(i)] != i) i = parent[std::size_t(i)] = parent[std::size_t(parent[std::size_t(i)])];
    return i;
}

/// A path across a face between two crossings, through a face vertex when `lens` (both on one edge).
struct Path {
    std::uint32_t from, to;
    Vec3 fromNormal{0.0}, toNormal{0.0};  ///< zero where unknown
    double fromAt = 0.0, toAt = 0.0;      ///< offsets along their edges
    bool lens = false;
    int side = 0;                 ///< the walk edge of a lens
    int fromSide = 0, toSide = 0; ///< the walk edges of its ends
    double lo = 0.0, hi = 0.0;    ///< a lens's span along its edge
    double along = 0.0, depth = 0.0;      ///< a lens's face vertex: along its edge, into the face
    std::array<double, 2> vertex{};       ///< the same in the face's (u, v)
    int region = 0;                       ///< the region of material it bounds (facePaths)
};

/// The point of a face at offset `along` on walk edge `side` and `depth` into the face, in (u, v).
std::array<double, 2> lensPoint(int side, double along, double depth) {
    switch (side) {
    case 0: return {along, depth};
    case 1: return {1.0 - depth, along};
    case 2: return {along, 1.0 - depth};
    default: return {depth, along};
    }
}

/// The least depth of a lens's face vertex (kFaceVertexGap, kMinLensRise).
double minDepth(const Path& p) { return std::max(kFaceVertexGap, kMinLensRise * (p.hi - p.lo)); }

/// A path's points in the face's (u, v): its ends, and a lens's face vertex between them.
std::vector<std::array<double, 2>> pathPoints(const Path& p) {
    std::vector<std::array<double, 2>> out{lensPoint(p.fromSide, p.fromAt, 0.0)};
    if (p.lens) out.push_back(p.vertex);
    out.push_back(lensPoint(p.toSide, p.toAt, 0.0));
    return out;
}

/// Where a path that is no lens crosses a sharp crease, the point of the face at which its ends'
/// tangent lines meet: its ends' normals make a cosine below creaseCosine and above its negative
/// (a fin's sides run alike and meet nowhere near), each meets the face at more than
/// kGrazingInFace (a grazing sheet's slice curls round before its tangent reaches a corner), and
/// the point lies strictly inside the face. There the surface's slice bends, and the cell's vertex
/// of a crease lies on the crease line through it (patch_vertex.h); the chord cuts the corner off.
std::optional<std::array<double, 2>> creaseCorner(const CellCrossings& cell, const Frame& f, const Path& p) {
    if (p.lens) return std::nullopt;
    const double cosine = glm::dot(p.fromNormal, p.toNormal);
    if (cosine >= cell.creaseCosine || cosine <= -cell.creaseCosine) return std::nullopt;
    const double a1 = p.fromNormal[f.u], b1 = p.fromNormal[f.v], a2 = p.toNormal[f.u], b2 = p.toNormal[f.v];
    const double l1 = std::hypot(a1, b1), l2 = std::hypot(a2, b2);
    if (l1 < kGrazingInFace || l2 < kGrazingInFace) return std::nullopt;
    const double det = a1 * b2 - b1 * a2;
    if (std::abs(det) <= kParallelSine * l1 * l2) return std::nullopt;
    const std::array<double, 2> x1 = lensPoint(p.fromSide, p.fromAt, 0.0), x2 = lensPoint(p.toSide, p.toAt, 0.0);
    const double c1 = a1 * x1[0] + b1 * x1[1], c2 = a2 * x2[0] + b2 * x2[1];
    const std::array<double, 2> corner{(c1 * b2 - b1 * c2) / det, (a1 * c2 - c1 * a2) / det};
    if (!(corner[0] > 0.0 && corner[0] < 1.0 && corner[1] > 0.0 && corner[1] < 1.0)) return std::nullopt;
    return corner;
}

/// A path's slice through the face as the self-crossing test reads it: pathPoints, through the
/// corner of a crease it crosses (creaseCorner) between its ends.
std::vector<std::array<double, 2>> slicePoints(const CellCrossings& cell, const Frame& f, const Path& p) {
    std::vector<std::array<double, 2>> out = pathPoints(p);
    if (const auto corner = creaseCorner(cell, f, p)) out.insert(out.begin() + 1, *corner);
    return out;
}

/// Whether two polylines in a face cross: a segment of one passes strictly through a segment of
/// the other.
bool polylinesCross(const std::vector<std::array<double, 2>>& a, const std::vector<std::array<double, 2>>& b) {
    const auto orient = [](const std::array<double, 2>& p, const std::array<double, 2>& q, const std::array<double, 2>& r) {
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
    };
    for (std::size_t i = 0; i + 1 < a.size(); ++i)
        for (std::size_t j = 0; j + 1 < b.size(); ++j) {
            const double o1 = orient(a[i], a[i + 1], b[j]), o2 = orient(a[i], a[i + 1], b[j + 1]);
            const double o3 = orient(b[j], b[j + 1], a[i]), o4 = orient(b[j], b[j + 1], a[i + 1]);
            if (((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0)) && ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0)))
                return true;
        }
    return false;
}

/// Whether two paths of a face cross (they share no end: every crossing ends one path).
bool pathsCross(const Path& p, const Path& q) { return polylinesCross(pathPoints(p), pathPoints(q)); }

/// Lenses on two edges of a face that meet at a corner are placed each on its own, and one's face
/// vertex may reach past the other's path: the slices of the surface cannot cross, but the chords
/// through the face vertices can, and the fans over them in the cell then pass through each other.
/// (tort.ngc at h = 0.5 mm, the lattice plane z = -2.442 at (3.94, -5.06): a lens 0.033 mm long on
/// one edge, its face vertex 0.062 mm in, crossed the path of a lens on the next edge, 0.011 mm
/// from their corner; two pairs of fan triangles crossed.) Where two paths cross, the deeper lens
/// (or the one lens) is brought halfway nearer its edge, down to its least depth, until they do
/// not; then the other lens. The face's data alone decides, so both cells sharing it agree.
void uncross(std::vector<Path>& paths) {
    const auto shallower = [&](Path& p) {
        if (!p.lens || p.depth <= minDepth(p)) return false;
        p.depth = std::max(minDepth(p), 0.5 * p.depth);
        p.vertex = lensPoint(p.side, p.along, p.depth);
        return true;
    };
    // Depths only fall, each to its least at most, so the sweeps end; a sweep that changed a
    // depth is followed by another, since a lens brought nearer its edge may now cross one it
    // went round.
    for (bool changed = true; changed;) {
        changed = false;
        for (std::size_t i = 0; i < paths.size(); ++i)
            for (std::size_t j = i + 1; j < paths.size(); ++j) {
                if (!paths[i].lens && !paths[j].lens) continue;
                Path* first = &paths[i];
                Path* second = &paths[j];
                if (!first->lens || (second->lens && second->depth > first->depth)) std::swap(first, second);
                for (int k = 0; k < kUncrossHalvings && pathsCross(*first, *second); ++k) {
                    if (!shallower(*first) && !shallower(*second)) break;
                    changed = true;
                }
            }
    }
}

/// The paths round the face's regions of material: each region's arcs in walk order, its
/// boundary leaving one and entering the next.
std::vector<Path> regionPaths(const std::vector<WalkCrossing>& walk, const std::vector<std::size_t>& arcs,
                              const std::vector<int>& region) {
    const std::size_t n = walk.size();
    std::vector<Path> paths;
    for (std::size_t r = 0; r < arcs.size(); ++r) {
        std::size_t next = r;
        for (std::size_t k = 1; k <= arcs.size(); ++k) {
            const std::size_t q = (r + k) % arcs.size();
            if (region[q] == region[r]) {
                next = q;
                break;
            }
        }
        const WalkCrossing& leave = walk[(arcs[r] + 1) % n];
        const WalkCrossing& enter = walk[arcs[next]];
        Path p{leave.id, enter.id, leave.normal, enter.normal, leave.at, enter.at};
        p.fromSide = leave.side;
        p.toSide = enter.side;
        if (leave.side == enter.side) {
            p.lens = true;
            p.side = leave.side;
            p.lo = std::min(leave.at, enter.at);
            p.hi = std::max(leave.at, enter.at);
        }
        p.region = region[r];
        paths.push_back(p);
    }
    return paths;
}

/// The face vertices of the lenses among the face's paths.
void placeFaceVertices(const CellCrossings& cell, const Frame& f, std::vector<Path>& paths) {
    // Face vertices: from the ends' tangent lines (cell_loops.h), else where the blend, on the
    // line into the face from the lens's middle (a fin's: below where its sides' tangents meet,
    // within the lens), first leaves the membership the edge has there;
    // a lens round others on its edge goes deeper. Worked in the lens's edge frame: along the
    // edge (its lattice offset) and into the face.
    const FaceField field(cell, f);
    std::vector<std::size_t> lenses;
    for (std::size_t k = 0; k < paths.size(); ++k)
        if (paths[k].lens) lenses.push_back(k);
    std::sort(lenses.begin(), lenses.end(),
              [&](std::size_t x, std::size_t y) { return paths[x].hi - paths[x].lo < paths[y].hi - paths[y].lo; });
    for (std::size_t li = 0; li < lenses.size(); ++li) {
        Path& p = paths[lenses[li]];
        const int alongAxis = p.side % 2 == 0 ? f.u : f.v, inAxis = p.side % 2 == 0 ? f.v : f.u;
        const double inSign = p.side == 0 || p.side == 3 ? 1.0 : -1.0;
        const double a1 = p.fromNormal[alongAxis], b1 = inSign * p.fromNormal[inAxis];
        const double a2 = p.toNormal[alongAxis], b2 = inSign * p.toNormal[inAxis];
        const double l1 = std::hypot(a1, b1), l2 = std::hypot(a2, b2);
        double along = 0.5 * (p.lo + p.hi), depth = -1.0;
        if (l1 > kInFace && l2 > kInFace) {
            // The tangent lines meet at (x, y); on the face's side (y > 0) the arc between the
            // ends turns by less than half a turn.
            const double det = a1 * b2 - b1 * a2;
            const double turn = std::acos(std::clamp((a1 * a2 + b1 * b2) / (l1 * l2), -1.0, 1.0));
            const double y = std::abs(det) > kParallelSine * l1 * l2 ? a1 * a2 * (p.toAt - p.fromAt) / det : 0.0;
            const double cosine = glm::dot(p.fromNormal, p.toNormal);
            const bool smooth = cosine >= cell.creaseCosine || std::min(l1, l2) < kGrazingInFace;
            // Ends whose normals are within the feature angle of opposite are a fin's two sides,
            // which run alike: no wedge's tip lies where their tangent lines meet, far off or past
            // the face. The face vertex keeps that point's place along the edge, within the lens
            // (the way the fin leans into the face), and takes the field's depth there. (Two ball
            // plunges of radius 15 h whose walls pass 0.053 h apart, the fin slanting across the
            // faces of a cell: on the face z = 1.5 its sides' tangents met past the face, the face
            // vertex went to its far edge, 0.999 h in, and its fan passed through another patch's,
            // over a lens 0.93 h deep in the face x = 9.5.)
            const bool fin = cosine <= -cell.creaseCosine;
            if (smooth) {
                // A circular arc over the chord c that turns by theta rises c/2 tan(theta/4).
                const double theta = y >= 0.0 ? turn : 2.0 * kPi - turn;
                depth = 0.5 * (p.hi - p.lo) * std::tan(0.25 * theta);
            } else if (y > 0.0) {
                along = std::clamp((a1 * p.fromAt * b2 - b1 * a2 * p.toAt) / det, p.lo, p.hi);
                if (!fin) depth = y;
            }
        }
        if (depth < 0.0) {
            const bool edgeIn = field.member(p.side, along);
            const auto differs = [&](double d) {
                const std::array<double, 2> uv = lensPoint(p.side, along, d);
                return (field.value(uv[0], uv[1]) < 0.0) != edgeIn;
            };
            depth = 0.5;
            for (int k = 1; k <= kDepthSamples; ++k) {
                const double d = double(k) / kDepthSamples;
                if (!differs(d)) continue;
                double lo = double(k - 1) / kDepthSamples, hi = d;
                for (int b = 0; b < kDepthBisections; ++b) (differs(0.5 * (lo + hi)) ? hi : lo) = 0.5 * (lo + hi);
                depth = 0.5 * (lo + hi);
                break;
            }
        }
        for (std::size_t lj = 0; lj < li; ++lj) {
            const Path& q = paths[lenses[lj]];
            if (q.side == p.side && p.lo <= q.lo && q.hi <= p.hi) depth = std::max(depth, q.depth + kNestedDepthStep);
        }
        p.depth = std::clamp(depth, minDepth(p), 1.0 - kFaceVertexGap);
        p.along = along;
    }
    for (Path& p : paths)
        if (p.lens) p.vertex = lensPoint(p.side, p.along, p.depth);
}

/// Whether two regions interleave round the face: arcs a < b < c < d in walk order with a and c
/// in one region and b and d in another. Regions of material in a face never do.
bool interleaved(const std::vector<int>& region) {
    const std::size_t n = region.size();
    for (std::size_t a = 0; a < n; ++a)
        for (std::size_t b = a + 1; b < n; ++b)
            for (std::size_t c = b + 1; c < n; ++c)
                for (std::size_t d = c + 1; d < n; ++d)
                    if (region[a] == region[c] && region[b] == region[d] && region[a] != region[b]) return true;
    return false;
}

/// The face rule samples the face on a grid of lines, and a strip of material thinner than the
/// grid's steps that cuts a corner of the face slantwise falls between its samples: the rule reads
/// the strip's two ends as two stubs, each a lens on its own edge. Within about a lens's least
/// depth of the corner those lenses cross even at that depth, which uncross cannot undo. Two
/// regions whose paths still cross overlap in the face as the rule itself draws them, and are
/// taken as one, unless that would interleave them with another region: then the strip's sides
/// run across the corner. (Two plunges of radius 15 h, their walls 0.026 h apart, leave a fin that
/// passes 0.004 h from a lattice point; 12 pairs of fan triangles crossed there.) Unites one pair
/// and says whether it did.
bool uniteCrossing(const std::vector<Path>& paths, std::vector<int>& region) {
    for (std::size_t i = 0; i < paths.size(); ++i)
        for (std::size_t j = i + 1; j < paths.size(); ++j) {
            const Path& p = paths[i];
            const Path& q = paths[j];
            if (p.region == q.region || (!p.lens && !q.lens) || !pathsCross(p, q)) continue;
            std::vector<int> united = region;
            std::replace(united.begin(), united.end(), q.region, p.region);
            if (interleaved(united)) continue;
            region = std::move(united);
            return true;
        }
    return false;
}

/// A lens may still cross another path of its own region at its least depth. Only a lens can: the
/// paths of a region join its arcs in walk order, so no two of them have ends that interleave
/// round the face's boundary, and straight chords between boundary points cross only where their
/// ends do. The region's boundary then passes through itself in the face, and the fans over the
/// loops through the two paths pass through each other. (boat-xyzac.ngc at h = 0.25 mm: a notch
/// 0.34 h long through a sheet 0.026 h thick, whose lens is at least 0.067 h deep, crossed the
/// sheet's path; 50 of the 196 pairs of triangles were such.) The other path is read as the
/// surface's slice, through the corner of a crease it crosses (slicePoints), not as its chord: the
/// crease's vertex in the cell lies on that corner's line, and a lens round the corner held it.
/// (boat-xyzac.ngc, the cells from (0.0443, 12.3186, -4.2875) along x: a notch 0.48 h long,
/// 0.15 h deep, opens into a pocket whose floor meets its wall 0.08 h from the notch's edge, and
/// the chord passed 0.49 h from the notch's tip; 42 of the 88 pairs.) Path i leaves arc i for the region's
/// next arc; where paths i and j cross (i < j, one region), the region's arcs after arc i through
/// arc j take a new region: path i then runs to the arc path j ran to, and path j to the one path i
/// ran to, the other pairing of their ends, and each part gets its own paths and its own patch.
/// Each part's arcs lie in one stretch of the walk that holds none of the other's, so no two
/// regions interleave. Every crossing still starts one path and ends one, so the cell's paths
/// still close into loops. Splits one region and says whether it did.
bool splitSelfCrossing(const CellCrossings& cell, const Frame& f, const std::vector<Path>& paths,
                       std::vector<int>& region) {
    // Each path's slice, made when a pair first needs it.
    std::vector<std::optional<std::vector<std::array<double, 2>>>> slices(paths.size());
    const auto slice = [&](std::size_t k) -> const std::vector<std::array<double, 2>>& {
        if (!slices[k]) slices[k] = slicePoints(cell, f, paths[k]);
        return *slices[k];
    };
    for (std::size_t i = 0; i < paths.size(); ++i)
        for (std::size_t j = i + 1; j < paths.size(); ++j) {
            const Path& p = paths[i];
            const Path& q = paths[j];
            if (p.region != q.region || (!p.lens && !q.lens) || !polylinesCross(slice(i), slice(j))) continue;
            const int fresh = *std::max_element(region.begin(), region.end()) + 1;
            for (std::size_t r = i + 1; r <= j; ++r)
                if (region[r] == p.region) region[r] = fresh;
            return true;
        }
    return false;
}

/// The face's paths, oriented in its own frame: material on their left seen from +a.
std::vector<Path> facePaths(const CellCrossings& cell, const Frame& f, bool severalOnAnEdge, bool joined) {
    std::vector<WalkCrossing> walk;
    for (int i = 0; i < 4; ++i) {
        const EdgeCrossings& e = cell.edges[std::size_t(f.edge[std::size_t(i)])];
        const bool backwards = i >= 2;
        const std::size_t n = e.ids.size();
        for (std::size_t k = 0; k < n; ++k) {
            const std::size_t j = backwards ? n - 1 - k : k;
            walk.push_back({e.ids[j], i, e.at[j], i + (backwards ? 1.0 - e.at[j] : e.at[j]),
                            e.normals.empty() ? Vec3(0.0) : e.normals[j]});
        }
    }
    const std::size_t n = walk.size();
    if (n == 0) return {};
    // Arcs in material, by the index of the crossing that enters them.
    std::vector<std::size_t> arcs;
    bool in = (cell.inside >> f.corner[0]) & 1;
    for (std::size_t k = 0; k < n; ++k) {
        in = !in;
        if (in) arcs.push_back(k);
    }
    std::vector<int> region(arcs.size());
    if (!severalOnAnEdge) {
        // Two arcs only when the corners alternate: joined, or each on its own.
        std::iota(region.begin(), region.end(), 0);
        if (arcs.size() == 2 && joined) region[1] = 0;
    } else {
        const FaceField field(cell, f);
        const std::vector<double> us = sampleLines(cell.edges[std::size_t(f.edge[0])], cell.edges[std::size_t(f.edge[2])]);
        const std::vector<double> vs = sampleLines(cell.edges[std::size_t(f.edge[3])], cell.edges[std::size_t(f.edge[1])]);
        const int nu = int(us.size()), nv = int(vs.size());
        std::vector<char> material(std::size_t(nu * nv));
        for (int j = 0; j < nv; ++j)
            for (int i = 0; i < nu; ++i) {
                bool m = false;
                if (j == 0) m = field.member(0, us[std::size_t(i)]);
                else if (j == nv - 1) m = field.member(2, us[std::size_t(i)]);
                else if (i == 0) m = field.member(3, vs[std::size_t(j)]);
                else if (i == nu - 1) m = field.member(1, vs[std::size_t(j)]);
                else m = field.value(us[std::size_t(i)], vs[std::size_t(j)]) < 0.0;
                material[std::size_t(j * nu + i)] = m;
            }
        std::vector<int> parent(material.size());
        std::iota(parent.begin(), parent.end(), 0);
        for (int j = 0; j < nv; ++j)
            for (int i = 0; i < nu; ++i) {
                const int k = j * nu + i;
                if (!material[std::size_t(k)]) continue;
                if (i + 1 < nu && material[std::size_t(k + 1)]) parent[std::size_t(find(parent, k))] = find(parent, k + 1);
                if (j + 1 < nv && material[std::size_t(k + nu)]) parent[std::size_t(find(parent, k))] = find(parent, k + nu);
            }
        // The first sample line strictly inside (lo, hi): one lies between any two crossings.
        const auto index = [](const std::vector<double>& lines, double lo) {
            return int(std::upper_bound(lines.begin(), lines.end(), lo) - lines.begin());
        };
        for (std::size_t r = 0; r < arcs.size(); ++r) {
            const WalkCrossing& enter = walk[arcs[r]];
            const WalkCrossing& leave = walk[(arcs[r] + 1) % n];
            int i = 0, j = 0;
            if (enter.side == leave.side && enter.walk < leave.walk) {
                // The arc lies on one edge: a sample inside it.
                const double lo = std::min(enter.at, leave.at);
                switch (enter.side) {
                case 0: i = index(us, lo), j = 0; break;
                case 1: i = nu - 1, j = index(vs, lo); break;
                case 2: i = index(us, lo), j = nv - 1; break;
                default: i = 0, j = index(vs, lo); break;
                }
            } else {
                // The arc holds the corner that follows its first crossing.
                const int c = (enter.side + 1) % 4;
                i = c == 1 || c == 2 ? nu - 1 : 0;
                j = c >= 2 ? nv - 1 : 0;
            }
            region[r] = find(parent, j * nu + i);
        }
    }
    // Where regions' paths cross at their lenses' least depth, the regions are one; then where a
    // region's own paths cross, it is split. Each unite leaves one region fewer and each split one
    // more, and no unite follows a split, so the loop ends after fewer passes than twice the arcs.
    for (bool split = false;;) {
        std::vector<Path> paths = regionPaths(walk, arcs, region);
        placeFaceVertices(cell, f, paths);
        uncross(paths);
        if (!split && uniteCrossing(paths, region)) continue;
        if (!splitSelfCrossing(cell, f, paths, region)) return paths;
        split = true;
    }
}

}  // namespace

std::vector<std::vector<std::uint32_t>> cellLoops(const CellCrossings& cell, const FaceVertexFn& faceVertex) {
    // Directed links (from, to) of the cell's paths. A face's own frame has material on the left
    // seen from +a: as cell_table.h orients, the face at offset 0 keeps that direction and the
    // face at offset 1 (seen from outside the cell, from +a) reverses it.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> links;
    for (int face = 0; face < kCellFaces; ++face) {
        const Frame f = frameOf(face);
        bool several = false;
        for (int e : f.edge) several = several || cell.edges[std::size_t(e)].ids.size() > 1;
        for (const Path& p : facePaths(cell, f, several, (cell.joined >> face) & 1)) {
            const std::uint32_t from = f.s ? p.to : p.from, to = f.s ? p.from : p.to;
            if (p.lens) {
                const std::uint32_t mid = faceVertex(face, from, to, p.vertex[0], p.vertex[1]);
                links.push_back({from, mid});
                links.push_back({mid, to});
            } else {
                links.push_back({from, to});
            }
        }
    }
    std::sort(links.begin(), links.end());
    for (std::size_t k = 1; k < links.size(); ++k)
        if (links[k].first == links[k - 1].first)
            throw std::logic_error("cellLoops: a crossing starts two paths (its edge disagrees with its corners)");
    std::vector<std::vector<std::uint32_t>> loops;
    std::vector<char> used(links.size(), 0);
    const auto linkFrom = [&](std::uint32_t id) {
        const auto it = std::lower_bound(links.begin(), links.end(), std::make_pair(id, std::uint32_t(0)));
        if (it == links.end() || it->first != id)
            throw std::logic_error("cellLoops: a crossing starts no path (its edge disagrees with its corners)");
        return std::size_t(it - links.begin());
    };
    for (std::size_t start = 0; start < links.size(); ++start) {
        if (used[start]) continue;
        std::vector<std::uint32_t> loop;
        for (std::size_t k = start; !used[k]; k = linkFrom(links[k].second)) {
            used[k] = 1;
            loop.push_back(links[k].first);
        }
        if (links[linkFrom(loop.back())].second != loop.front())
            throw std::logic_error("cellLoops: paths do not close into loops");
        loops.push_back(std::move(loop));
    }
    return loops;
}

}  // namespace dexelmill::detail
