#include "dexelmill/refine/refine.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

#include "refine/detail/windows.h"

namespace dexelmill {

namespace {

/// A sub-triangle must face its parent's way at a cosine above this: refinement follows the
/// surface, it never turns a piece of it over (a smooth part tilts the halves by the curvature
/// over half an edge, a few degrees; a crease the parent cut across by up to 45 degrees).
constexpr double kMinCosine = 0.1;
/// A sub-triangle whose doubled area is below this times its longest squared edge is a sliver:
/// the split that makes it is refused (checkMesh's degenerate limit is far below).
constexpr double kSliver = 1e-4;

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

/// The undirected edges of a mesh: per triangle corner slot 3t + k (the edge from corner k to
/// corner k + 1) its edge, and per edge its ends and the two triangles that share it.
struct EdgeTable {
    std::vector<std::uint32_t> edgeOf;
    std::vector<std::array<std::uint32_t, 2>> ends;
    std::vector<std::array<std::uint32_t, 2>> triangles;  ///< kNone where not exactly two
};

/// The edge table from the directed edges grouped by their first vertex: an edge's owner is its
/// slot going up in vertex index (or its only slot), and its twin the slot going back. An edge
/// with more than one slot each way, or none back, keeps no triangles (it is never split).
EdgeTable buildEdges(const Mesh& mesh) {
    const std::size_t slots = 3 * mesh.triangles.size();
    const auto from = [&](std::size_t s) { return mesh.triangles[s / 3][s % 3]; };
    const auto to = [&](std::size_t s) { return mesh.triangles[s / 3][(s % 3 + 1) % 3]; };
    // Slots by first vertex (counting sort).
    std::vector<std::uint32_t> start(mesh.vertices.size() + 1, 0), bySource(slots);
    for (std::size_t s = 0; s < slots; ++s) ++start[from(s) + 1];
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) start[v + 1] += start[v];
    {
        std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
        for (std::size_t s = 0; s < slots; ++s) bySource[fill[from(s)]++] = std::uint32_t(s);
    }
    // Per slot: its twin (kNone if none or several) and whether another slot runs the same way.
    std::vector<std::uint32_t> twin(slots, kNone);
    std::vector<char> shared(slots, 0);
    tbb::parallel_for(std::size_t(0), slots, [&](std::size_t s) {
        const std::uint32_t a = from(s), b = to(s);
        if (a == b) return void(shared[s] = 1);  // a corner repeated: no edge to split
        std::size_t back = 0;
        for (std::uint32_t i = start[b]; i < start[b + 1]; ++i)
            if (to(bySource[i]) == a) twin[s] = bySource[i], ++back;
        for (std::uint32_t i = start[a]; i < start[a + 1]; ++i)
            if (bySource[i] != s && to(bySource[i]) == b) shared[s] = 1;
        if (back != 1) twin[s] = kNone, shared[s] = 1;
    });
    // Owners number the edges in slot order; the others take their twin's number.
    EdgeTable e;
    e.edgeOf.resize(slots);
    const auto owner = [&](std::size_t s) { return from(s) < to(s) || twin[s] == kNone; };
    std::uint32_t edges = 0;
    for (std::size_t s = 0; s < slots; ++s)
        if (owner(s)) e.edgeOf[s] = edges++;
    e.ends.resize(edges);
    e.triangles.resize(edges);
    tbb::parallel_for(std::size_t(0), slots, [&](std::size_t s) {
        if (!owner(s)) {
            e.edgeOf[s] = e.edgeOf[twin[s]];
            return;
        }
        const std::uint32_t id = e.edgeOf[s];
        e.ends[id] = {std::min(from(s), to(s)), std::max(from(s), to(s))};
        e.triangles[id] = shared[s] ? std::array<std::uint32_t, 2>{kNone, kNone}
                                    : std::array<std::uint32_t, 2>{std::uint32_t(s / 3), twin[s] / 3};
    });
    return e;
}

Vec3 unit(const Vec3& v) {
    const double n = glm::length(v);
    return n > 0.0 ? v / n : Vec3(0.0);
}

/// Local indices of a triangle being split: corners 0-2, midpoint of edge k (corner k to k + 1)
/// at 3 + k.
using Local = std::array<int, 3>;

/// Whether the sub-triangle (a, b, c) of a parent with unit normal `n` is acceptable.
bool goodPiece(const std::array<Vec3, 6>& p, const Local& t, const Vec3& n) {
    const Vec3 s = glm::cross(p[t[1]] - p[t[0]], p[t[2]] - p[t[0]]);
    const double len = glm::length(s);
    const double longest = std::max({glm::dot(p[t[1]] - p[t[0]], p[t[1]] - p[t[0]]),
                                      glm::dot(p[t[2]] - p[t[1]], p[t[2]] - p[t[1]]),
                                      glm::dot(p[t[0]] - p[t[2]], p[t[0]] - p[t[2]])});
    return len > kSliver * longest && glm::dot(s, n) > kMinCosine * len;
}

/// The pieces of a triangle whose edges in `mask` (bit k: edge k) are split, oriented as the
/// triangle; positions `p` as Local. Returns the count, 0 if some piece would fold or be a sliver
/// (for two split edges, the quad's other diagonal is tried before giving up).
int splitPieces(const std::array<Vec3, 6>& p, unsigned mask, const Vec3& n, std::array<Local, 4>& out) {
    const int bits = int(mask & 1u) + int((mask >> 1) & 1u) + int((mask >> 2) & 1u);
    // Rotation r: local corner i is the triangle's corner (i + r) % 3.
    int r = 0;
    if (bits == 1) r = mask == 1u ? 0 : (mask == 2u ? 1 : 2);
    if (bits == 2) r = ((mask == 3u ? 2 : (mask == 6u ? 0 : 1)) + 1) % 3;  // the unsplit edge to local 2
    const auto c = [&](int i) { return (i + r) % 3; };
    const auto m = [&](int i) { return 3 + (i + r) % 3; };
    int count = 0;
    if (bits == 1) {
        out[0] = {c(0), m(0), c(2)};
        out[1] = {m(0), c(1), c(2)};
        count = 2;
    } else if (bits == 2) {
        out[0] = {m(0), c(1), m(1)};
        const std::array<Local, 2> viaC0{Local{c(0), m(0), m(1)}, Local{c(0), m(1), c(2)}};
        const std::array<Local, 2> viaM0{Local{c(0), m(0), c(2)}, Local{m(0), m(1), c(2)}};
        const bool c0First = glm::length(p[c(0)] - p[m(1)]) <= glm::length(p[m(0)] - p[c(2)]);
        const std::array<Local, 2>& first = c0First ? viaC0 : viaM0;
        const std::array<Local, 2>& second = c0First ? viaM0 : viaC0;
        if (goodPiece(p, first[0], n) && goodPiece(p, first[1], n)) {
            out[1] = first[0], out[2] = first[1];
        } else {
            out[1] = second[0], out[2] = second[1];
        }
        count = 3;
    } else if (bits == 3) {
        out[0] = {c(0), m(0), m(2)};
        out[1] = {m(0), c(1), m(1)};
        out[2] = {m(2), m(1), c(2)};
        out[3] = {m(0), m(1), m(2)};
        count = 4;
    }
    for (int i = 0; i < count; ++i)
        if (!goodPiece(p, out[i], n)) return 0;
    return count;
}

/// One round: tests the edges `candidate` marks, splits those off the exact surface.
/// Returns the number of edges split.
/// A new vertex and pieces replace each split edge and its triangles (in `refined`, which may
/// then fold against its vertices' normals: see refineRound); `parent` receives each piece's
/// triangle in `mesh`. Returns the number of edges split.
std::size_t buildPieces(const Mesh& mesh, const EdgeTable& edges, const std::vector<char>& split,
                        const std::vector<Vec3>& at, Mesh& refined, std::vector<std::uint32_t>& parent) {
    refined = mesh;
    parent.resize(mesh.triangles.size());
    for (std::uint32_t t = 0; t < parent.size(); ++t) parent[t] = t;
    std::vector<std::uint32_t> newVertex(split.size(), kNone);
    std::size_t added = 0;
    for (std::size_t e = 0; e < split.size(); ++e) {
        if (!split[e]) continue;
        newVertex[e] = std::uint32_t(refined.vertices.size());
        refined.vertices.push_back(at[e]);
        ++added;
    }
    // Each split triangle's pieces: the first replaces it, the others go after the old triangles,
    // in triangle order (counted first, so that both passes run in parallel).
    const auto pieces = [&](std::size_t t, std::array<Local, 4>& out, std::array<std::uint32_t, 6>& ids) {
        unsigned bits = 0;
        std::array<Vec3, 6> p;
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t e = edges.edgeOf[3 * t + k];
            ids[k] = mesh.triangles[t][k];
            ids[3 + k] = newVertex[e];
            p[k] = mesh.vertices[ids[k]];
            p[3 + k] = split[e] ? at[e] : Vec3(0.0);
            if (split[e]) bits |= 1u << k;
        }
        return bits ? splitPieces(p, bits, unit(mesh.areaVector(t)), out) : 0;
    };
    const std::size_t nt = mesh.triangles.size();
    std::vector<std::uint32_t> extra(nt + 1, 0);
    tbb::parallel_for(std::size_t(0), nt, [&](std::size_t t) {
        std::array<Local, 4> out;
        std::array<std::uint32_t, 6> ids;
        const int count = pieces(t, out, ids);
        extra[t + 1] = count > 1 ? std::uint32_t(count - 1) : 0;
    });
    for (std::size_t t = 0; t < nt; ++t) extra[t + 1] += extra[t];
    refined.triangles.resize(nt + extra[nt]);
    parent.resize(nt + extra[nt]);
    tbb::parallel_for(std::size_t(0), nt, [&](std::size_t t) {
        std::array<Local, 4> out;
        std::array<std::uint32_t, 6> ids;
        const int count = pieces(t, out, ids);
        if (count == 0) return;
        const auto piece = [&](const Local& l) { return Mesh::Triangle{ids[l[0]], ids[l[1]], ids[l[2]]}; };
        refined.triangles[t] = piece(out[0]);
        for (int i = 1; i < count; ++i) {
            refined.triangles[nt + extra[t] + i - 1] = piece(out[i]);
            parent[nt + extra[t] + i - 1] = std::uint32_t(t);
        }
    });
    return added;
}

/// The triangles of `mesh` that fold against their vertices' normals, or have no area (checkMesh),
/// and the check itself.
MeshCheck foldedTriangles(Mesh& mesh, std::vector<std::uint32_t>& folded) {
    FoldRepair none;
    none.rounds = 0;
    none.pull = [](std::uint32_t, int, Vec3&, const std::vector<std::uint32_t>&) { return false; };
    return repairAndCheckMesh(mesh, none, nullptr, &folded);
}

/// One round: tests the edges `candidate` marks, splits those off the exact surface. Returns the
/// number of edges split, and the check of the mesh it leaves in `check`.
std::size_t refineRound(Mesh& mesh, const EdgeTable& edges, const std::vector<char>& candidate, const Box& stock,
                        const ToolPath& path, const ToolTable& tools, const RefineOptions& o, RefineStats& stats,
                        MeshCheck& check) {
    const std::size_t nEdges = edges.ends.size();
    // One window per candidate edge, along the axis nearest its two triangles' mean normal.
    std::vector<std::uint32_t> asked;
    for (std::size_t e = 0; e < nEdges; ++e)
        if (candidate[e] && edges.triangles[e][0] != kNone) asked.push_back(std::uint32_t(e));
    std::vector<detail::Window> windows(asked.size());
    std::vector<char> facing(asked.size(), 0);
    tbb::parallel_for(std::size_t(0), asked.size(), [&](std::size_t i) {
        const std::uint32_t e = asked[i];
        const Vec3 n = unit(mesh.areaVector(edges.triangles[e][0])) + unit(mesh.areaVector(edges.triangles[e][1]));
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (std::abs(n[a]) > std::abs(n[axis])) axis = a;
        if (!(std::abs(n[axis]) > 0.0)) return;  // the two triangles face apart: a fin, left alone
        windows[i].point = 0.5 * (mesh.vertices[edges.ends[e][0]] + mesh.vertices[edges.ends[e][1]]);
        windows[i].axis = axis;
        windows[i].outward = n[axis] > 0.0;
        facing[i] = 1;
    });
    std::size_t kept = 0;
    for (std::size_t i = 0; i < asked.size(); ++i)
        if (facing[i]) asked[kept] = asked[i], windows[kept] = windows[i], ++kept;
    asked.resize(kept);
    windows.resize(kept);
    stats.queries += windows.size();
    const std::vector<double> offsets =
        detail::exactCrossings(windows, o.window, stock, path, tools, o.removeShankMaterial);

    // Proposed splits: the exact surface point on the edge's window.
    std::vector<char> split(nEdges, 0);
    std::vector<Vec3> at(nEdges);
    std::vector<double> moved(nEdges, 0.0);
    for (std::size_t i = 0; i < asked.size(); ++i) {
        const double d = offsets[i];
        if (std::isnan(d)) {
            ++stats.noCrossing;
            continue;
        }
        if (std::abs(d) <= o.tolerance) continue;
        const std::uint32_t e = asked[i];
        Vec3 q = windows[i].point;
        q[windows[i].axis] += d;
        split[e] = 1;
        at[e] = q;
        moved[e] = std::abs(d) / glm::length(mesh.vertices[edges.ends[e][1]] - mesh.vertices[edges.ends[e][0]]);
    }

    const auto mask = [&](std::size_t t) {
        unsigned bits = 0;
        for (int k = 0; k < 3; ++k)
            if (split[edges.edgeOf[3 * t + k]]) bits |= 1u << k;
        return bits;
    };
    const auto positions = [&](std::size_t t) {
        std::array<Vec3, 6> p;
        for (int k = 0; k < 3; ++k) {
            p[k] = mesh.vertices[mesh.triangles[t][k]];
            const std::uint32_t e = edges.edgeOf[3 * t + k];
            p[3 + k] = split[e] ? at[e] : Vec3(0.0);
        }
        return p;
    };
    // Refuse splits until every split triangle's pieces are good: the most displaced edge of a bad
    // triangle goes first, and its other triangle is looked at again.
    std::vector<std::uint32_t> work;
    const auto settle = [&] {
        std::array<Local, 4> pieces;
        while (!work.empty()) {
            const std::uint32_t t = work.back();
            work.pop_back();
            const unsigned bits = mask(t);
            if (!bits) continue;
            const Vec3 n = unit(mesh.areaVector(t));
            if (splitPieces(positions(t), bits, n, pieces) > 0) continue;
            std::uint32_t worst = kNone;
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t e = edges.edgeOf[3 * t + k];
                if (split[e] && (worst == kNone || moved[e] > moved[worst])) worst = e;
            }
            split[worst] = 0;
            ++stats.refused;
            work.push_back(t);
            for (std::uint32_t other : edges.triangles[worst])
                if (other != t) work.push_back(other);
        }
    };
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        if (mask(t)) work.push_back(std::uint32_t(t));
    settle();

    // Whether a triangle folds against its vertices' normals depends on the stars around its
    // corners, which the pieces' test cannot see. Where the refined mesh folds, every split of the
    // folded piece's parent, and of the triangles around the parent's corners, is refused: those
    // stars are then the unrefined mesh's, which did not fold. Refusals only grow, so this ends.
    Mesh refined;
    std::vector<std::uint32_t> parent, folded;
    std::size_t added = 0;
    for (;;) {
        added = buildPieces(mesh, edges, split, at, refined, parent);
        check = foldedTriangles(refined, folded);
        if (folded.empty() || added == 0) break;
        std::vector<char> corner(mesh.vertices.size(), 0);
        for (std::uint32_t t : folded)
            for (std::uint32_t v : mesh.triangles[parent[t]]) corner[v] = 1;
        std::size_t refused = 0;
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            const Mesh::Triangle& tri = mesh.triangles[t];
            if (!corner[tri[0]] && !corner[tri[1]] && !corner[tri[2]]) continue;
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t e = edges.edgeOf[3 * t + k];
                if (!split[e]) continue;
                split[e] = 0;
                ++refused;
                // The triangles across the edge lose a split too: their pieces are tested again.
                for (std::uint32_t other : edges.triangles[e]) work.push_back(other);
            }
        }
        stats.refused += refused;
        if (refused == 0) break;
        settle();
    }
    mesh = std::move(refined);
    stats.split += added;
    return added;
}

}  // namespace

void refineMesh(Mesh& mesh, const Box& stock, const ToolPath& path, const ToolTable& tools,
                const RefineOptions& options, RefineStats* stats) {
    RefineStats local;
    RefineStats& st = stats ? *stats : local;
    std::size_t firstNew = 0;
    bool checked = false;
    for (int round = 0; round < options.rounds && !mesh.empty(); ++round) {
        const double need = kRoundBytesPerTriangle * double(mesh.triangles.size());
        if (options.memoryBytes > 0.0 && need > options.memoryBytes) {
            st.roundNeeded = need;
            break;
        }
        const EdgeTable edges = buildEdges(mesh);
        // The first round tests every edge; later rounds only the edges the last one made (the
        // others were within the tolerance, or refused).
        std::vector<char> candidate(edges.ends.size());
        for (std::size_t e = 0; e < edges.ends.size(); ++e) candidate[e] = edges.ends[e][1] >= firstNew;
        const std::size_t before = mesh.vertices.size();
        checked = true;
        ++st.rounds;
        if (refineRound(mesh, edges, candidate, stock, path, tools, options, st, st.check) == 0) break;
        firstNew = before;
    }
    if (!checked) st.check = checkMesh(mesh);
}

}  // namespace dexelmill
