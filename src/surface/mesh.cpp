#include "dexelmill/surface/mesh.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include "memory/pages.h"
#include "surface/stars.h"

namespace dexelmill {

Box Mesh::bounds() const {
    Box b;
    for (const Vec3& v : vertices) b.expand(v);
    return b;
}

Vec3 Mesh::areaVector(std::size_t t) const {
    const Triangle& tri = triangles[t];
    const Vec3& a = vertices[tri[0]];
    return glm::cross(vertices[tri[1]] - a, vertices[tri[2]] - a);
}

double meshVolume(const Mesh& mesh) {
    // Divergence theorem: V = 1/6 sum a . (b x c), taken relative to the bounding-box centre so
    // that far-off parts do not lose digits; summed per range and reduced in a fixed order.
    const Vec3 c = mesh.vertices.empty() ? Vec3(0.0) : mesh.bounds().center();
    const double v6 = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 8192), 0.0,
        [&](const tbb::blocked_range<std::size_t>& r, double sum) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const Mesh::Triangle& t = mesh.triangles[i];
                const Vec3 a = mesh.vertices[t[0]] - c, b = mesh.vertices[t[1]] - c, d = mesh.vertices[t[2]] - c;
                sum += glm::dot(a, glm::cross(b, d));
            }
            return sum;
        },
        [](double a, double b) { return a + b; });
    return v6 / 6.0;
}

namespace {

using detail::StarChunks;
using detail::Stars;

/// The vertices' unit normals (as the check takes them).
using Normals = std::vector<glm::vec3, NoZeroAllocator<glm::vec3>>;

/// The vertices of corner `corner` (3 t + k)'s triangle after and before its own: the edges it
/// leaves its vertex by (to `out`) and enters it by (from `in`).
struct CornerSides {
    std::uint32_t out, in;
};

inline CornerSides cornerSides(const Mesh& mesh, std::uint32_t corner) {
    constexpr int kNext[3] = {1, 2, 0}, kPrev[3] = {2, 0, 1};
    const Mesh::Triangle& t = mesh.triangles[corner / 3];
    const int k = int(corner % 3);
    return {t[kNext[k]], t[kPrev[k]]};
}

/// The area vector of a corner of the star of the vertex at pv: the same for each corner of a
/// triangle, taken from this one.
inline Vec3 cornerArea(const Mesh& mesh, const CornerSides& c, const Vec3& pv) {
    return glm::cross(mesh.vertices[c.out] - pv, mesh.vertices[c.in] - pv);
}

/// A vertex's normal from the sum of its star's area vectors: unit, zero without area.
inline glm::vec3 unitNormal(const Vec3& sum) {
    const double l = glm::length(sum);
    return l > 0.0 ? glm::vec3(sum / l) : glm::vec3(0.0f);
}

/// Vertex v's normal as the check takes it: its star's area vectors summed in star order.
template <class StarsT>
glm::vec3 checkNormal(const Mesh& mesh, const StarsT& stars, std::uint32_t v) {
    Vec3 sum(0.0);
    const Vec3& pv = mesh.vertices[v];
    for (const std::uint32_t* c = stars.begin(v); c != stars.end(v); ++c) sum += cornerArea(mesh, cornerSides(mesh, *c), pv);
    return unitNormal(sum);
}

/// What the pass over the vertices finds.
struct VertexCounts {
    std::size_t edges = 0, boundary = 0, nonManifold = 0, misoriented = 0, unused = 0;
};

/// One vertex's part of the pass over the stars: its normal (the area-weighted mean direction
/// of its triangles; zero without area around it) and its edges' counts.
///
/// Every edge at a vertex v shows in v's own star: triangle (v, a, b) walks v -> a and b -> v.
/// The edges to each neighbour w > v are counted by direction (each undirected edge once, at its
/// smaller end): used once it is a boundary edge; more than twice, non-manifold; twice in one
/// direction, misoriented.
class VertexVisit {
public:
    glm::vec3 operator()(const Mesh& mesh, std::uint32_t v, const std::uint32_t* first, const std::uint32_t* last,
                         VertexCounts& c) {
        const std::size_t n = std::size_t(last - first);
        c.unused += n == 0;
        std::uint32_t* outs = outStack_;
        std::uint32_t* ins = inStack_;
        if (n > kStack) {
            outHeap_.resize(n);
            inHeap_.resize(n);
            outs = outHeap_.data();
            ins = inHeap_.data();
        }
        std::size_t nOut = 0, nIn = 0;
        Vec3 sum(0.0);
        const Vec3& pv = mesh.vertices[v];
        for (const std::uint32_t* i = first; i != last; ++i) {
            const CornerSides sides = cornerSides(mesh, *i);
            const std::uint32_t out = sides.out, in = sides.in;
            sum += cornerArea(mesh, sides, pv);
            if (out > v) outs[nOut++] = out;
            if (in > v) ins[nIn++] = in;
        }
        // Sorted, each list holds a neighbour's uses in one direction as a run; walking the two
        // together meets each distinct neighbour once (a star has a handful of corners, so an
        // insertion sort is quickest).
        sortSmall(outs, nOut);
        sortSmall(ins, nIn);
        // The common case, a closed oriented star: the same neighbours each way, each once.
        // (Compared in a loop: std::equal calls memcmp for these few words.)
        bool closed = nOut == nIn;
        for (std::size_t k = 0; closed && k < nOut; ++k) closed = outs[k] == ins[k] && (k == 0 || outs[k] != outs[k - 1]);
        if (closed) {
            c.edges += nOut;
            return unitNormal(sum);
        }
        std::size_t i = 0, j = 0;
        while (i < nOut || j < nIn) {
            const std::uint32_t w = j == nIn || (i < nOut && outs[i] < ins[j]) ? outs[i] : ins[j];
            std::size_t forward = 0, backward = 0;
            for (; i < nOut && outs[i] == w; ++i) ++forward;
            for (; j < nIn && ins[j] == w; ++j) ++backward;
            ++c.edges;
            const std::size_t uses = forward + backward;
            if (uses == 1) ++c.boundary;
            else if (uses > 2) ++c.nonManifold;
            else if (forward != 1) ++c.misoriented;
        }
        return unitNormal(sum);
    }

private:
    static void sortSmall(std::uint32_t* a, std::size_t n) {
        if (n > kStack) {
            std::sort(a, a + n);
            return;
        }
        for (std::size_t k = 1; k < n; ++k) {
            const std::uint32_t x = a[k];
            std::size_t m = k;
            for (; m > 0 && a[m - 1] > x; --m) a[m] = a[m - 1];
            a[m] = x;
        }
    }

    // The neighbours w > v reached by an edge leaving v (outs) and entering it (ins): on the
    // stack for ordinary stars.
    static constexpr std::size_t kStack = 32;
    std::uint32_t outStack_[kStack], inStack_[kStack];
    std::vector<std::uint32_t> outHeap_, inHeap_;
};

VertexCounts addCounts(VertexCounts a, const VertexCounts& b) {
    a.edges += b.edges, a.boundary += b.boundary, a.nonManifold += b.nonManifold;
    a.misoriented += b.misoriented, a.unused += b.unused;
    return a;
}

/// One pass over the vertices' stars, chunk by chunk where the stars come so: every vertex's
/// normal and the edge counts (VertexVisit).
VertexCounts vertexPass(const Mesh& mesh, const StarChunks& stars, Normals& normal) {
    const std::size_t nv = mesh.vertices.size();
    detail::reservePopulated(normal, nv);
    normal.resize(nv);
    if (!stars.chunked())
        return tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, nv, 4096), VertexCounts{},
            [&](const tbb::blocked_range<std::size_t>& rv, VertexCounts c) {
                VertexVisit visit;
                const Stars& all = stars.whole();
                for (std::size_t v = rv.begin(); v < rv.end(); ++v) {
                    const auto w = std::uint32_t(v);
                    normal[v] = visit(mesh, w, all.begin(w), all.end(w), c);
                }
                return c;
            },
            addCounts);
    struct Chunk {
        Stars stars;
        std::vector<std::uint64_t> scratch;
    };
    tbb::enumerable_thread_specific<Chunk> chunk;
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, stars.chunkCount(), 1), VertexCounts{},
        [&](const tbb::blocked_range<std::size_t>& rc, VertexCounts c) {
            VertexVisit visit;
            Chunk& mine = chunk.local();
            const Stars& local = mine.stars;
            for (std::size_t k = rc.begin(); k < rc.end(); ++k) {
                stars.build(k, mine.stars, mine.scratch);
                const auto end = std::uint32_t(local.first + local.offset.size() - 1);
                for (std::uint32_t v = local.first; v < end; ++v) normal[v] = visit(mesh, v, local.begin(v), local.end(v), c);
            }
            return c;
        },
        addCounts);
}

/// What the pass over the triangles finds.
struct TriangleCounts {
    std::size_t degenerate = 0, folded = 0;
    double area = 0.0, volume6 = 0.0;
    /// Folded, nearly folded (with a margin) and degenerate triangles: the ones to repair.
    std::vector<std::uint32_t> suspects;
};

/// The fold test of one triangle, shared by the pass over the triangles and the repair.
struct Facing {
    bool degenerate = true;  ///< a repeated index, or (numerically) no area
    Vec3 areaVector{0.0};    ///< (b - a) x (d - a): twice the area, along the normal
    double twiceArea = 0.0;
    double facing = 0.0;     ///< the area vector's dot product with `sum`
    Vec3 sum{0.0};           ///< the sum of the vertices' unit normals

    /// Facing its vertices' area-weighted normals at a cosine below minCosine (at 0, a triangle
    /// to repair, and folded if foldedByAngleToo finds it so).
    bool below(double minCosine) const { return facing < minCosine * twiceArea * glm::length(sum); }
};

inline Facing facingOf(const Mesh::Triangle& tri, const Vec3& a, const Vec3& b, const Vec3& d,
                       const Normals& normal) {
    Facing f;
    const Vec3 ab = b - a, ad = d - a;
    f.areaVector = glm::cross(ab, ad);
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) return f;
    f.twiceArea = glm::length(f.areaVector);
    const Vec3 bd = d - b;
    const double longest2 = std::max({glm::dot(ab, ab), glm::dot(bd, bd), glm::dot(ad, ad)});
    if (!(f.twiceArea > tol::kDegenerateTriangle * longest2)) return f;
    f.degenerate = false;
    f.sum = Vec3(normal[tri[0]]) + Vec3(normal[tri[1]]) + Vec3(normal[tri[2]]);
    f.facing = glm::dot(f.areaVector, f.sum);
    return f;
}

/// Adds triangle t to the sums of trianglePass.
inline void addTriangle(const Mesh& mesh, const Normals& normal, const Vec3& centre, double minCosine,
                        std::size_t t, TriangleCounts& c) {
    const Mesh::Triangle& tri = mesh.triangles[t];
    const Vec3& a = mesh.vertices[tri[0]];
    const Vec3& b = mesh.vertices[tri[1]];
    const Vec3& d = mesh.vertices[tri[2]];
    const Facing f = facingOf(tri, a, b, d, normal);
    // Six times the signed volume of the tetrahedron (centre, a, b, d): (a - centre) . ((b - a) x
    // (d - a)), the same in exact arithmetic as the triple product about the centre, since the
    // terms the shift adds are orthogonal to a - centre.
    c.volume6 += glm::dot(a - centre, f.areaVector);
    if (f.degenerate) {
        ++c.degenerate;
        c.suspects.push_back(std::uint32_t(t));
        return;
    }
    c.area += 0.5 * f.twiceArea;
    c.folded += f.facing < 0.0;
    if (f.facing < 0.0 || (minCosine > 0.0 && f.below(minCosine))) c.suspects.push_back(std::uint32_t(t));
}

/// One pass over the triangles: degenerate ones, area, six times the enclosed volume (about
/// `centre`), those facing against the sum of their vertices' unit normals (foldedByAngleToo tells
/// which of them fold), and the suspects (those, degenerate ones, and with minCosine > 0 those
/// facing their vertices' normals at a cosine below it). Ranges are reduced in a fixed order, so
/// the sums do not depend on the thread count.
TriangleCounts trianglePass(const Mesh& mesh, const Normals& normal, const Vec3& centre,
                            double minCosine = 0.0) {
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 8192), TriangleCounts{},
        [&](const tbb::blocked_range<std::size_t>& rt, TriangleCounts c) {
            for (std::size_t t = rt.begin(); t < rt.end(); ++t) addTriangle(mesh, normal, centre, minCosine, t, c);
            return c;
        },
        [](TriangleCounts a, const TriangleCounts& b) {
            a.degenerate += b.degenerate;
            a.folded += b.folded;
            a.area += b.area;
            a.volume6 += b.volume6;
            a.suspects.insert(a.suspects.end(), b.suspects.begin(), b.suspects.end());
            return a;
        });
}

/// The sums of trianglePass over some triangles, in their order.
TriangleCounts triangleSums(const Mesh& mesh, const Normals& normal, const Vec3& centre,
                            const std::vector<std::uint32_t>& triangles) {
    TriangleCounts c;
    for (std::uint32_t t : triangles) addTriangle(mesh, normal, centre, 0.0, t, c);
    return c;
}

/// Whether triangle t folds, nearly folds or is degenerate (the test of trianglePass).
bool suspect(const Mesh& mesh, const Normals& normal, std::uint32_t t, double minCosine) {
    const Mesh::Triangle& tri = mesh.triangles[t];
    const Facing f = facingOf(tri, mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]], normal);
    return f.degenerate || f.below(minCosine);
}

/// Sorts a list of indices and drops repeats.
void sortUnique(std::vector<std::uint32_t>& v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
}

/// The vertices of some triangles, each once.
std::vector<std::uint32_t> verticesOf(const Mesh& mesh, const std::vector<std::uint32_t>& triangles) {
    std::vector<std::uint32_t> out;
    for (std::uint32_t t : triangles)
        for (std::uint32_t v : mesh.triangles[t]) out.push_back(v);
    sortUnique(out);
    return out;
}

/// The triangles around any of some vertices, each once.
std::vector<std::uint32_t> trianglesAround(const StarChunks& stars, const std::vector<std::uint32_t>& vertices) {
    std::vector<std::uint32_t> out;
    for (std::uint32_t v : vertices)
        for (const std::uint32_t* c = stars.begin(v); c != stars.end(v); ++c) out.push_back(*c / 3);
    sortUnique(out);
    return out;
}

/// The vertices joined to v by an edge, each once, into `out`.
void neighboursOf(const Mesh& mesh, const StarChunks& stars, std::uint32_t v, std::vector<std::uint32_t>& out) {
    out.clear();
    for (const std::uint32_t* c = stars.begin(v); c != stars.end(v); ++c)
        for (std::uint32_t w : mesh.triangles[*c / 3])
            if (w != v) out.push_back(w);
    sortUnique(out);
}

/// What a repair changed: the first position of every moved vertex and the first normal of every
/// vertex whose normal was recomputed.
struct RepairLog {
    std::vector<std::pair<std::uint32_t, Vec3>> positions;
    std::vector<std::pair<std::uint32_t, glm::vec3>> normals;
    std::vector<bool> moved, renormalised;

    explicit RepairLog(std::size_t vertices) : moved(vertices, false), renormalised(vertices, false) {}
    void position(std::uint32_t v, const Vec3& first) {
        if (!moved[v]) moved[v] = true, positions.push_back({v, first});
    }
    void normal(std::uint32_t v, const glm::vec3& first) {
        if (!renormalised[v]) renormalised[v] = true, normals.push_back({v, first});
    }
};

/// Keeps the triangles of `triangles` that are still suspect.
void keepSuspects(const Mesh& mesh, const Normals& normal, double minCosine,
                  std::vector<std::uint32_t>& triangles) {
    triangles.erase(std::remove_if(triangles.begin(), triangles.end(),
                                   [&](std::uint32_t t) { return !suspect(mesh, normal, t, minCosine); }),
                    triangles.end());
}

/// The last resort of pullBack: each vertex of a triangle still suspect tries the candidate
/// positions it is offered, and keeps the one that leaves the fewest suspect triangles around it
/// and its neighbours (their normals follow the move).
void tryCandidates(Mesh& mesh, const StarChunks& stars, Normals& normal,
                   std::vector<std::uint32_t>& suspects, const FoldRepair& repair, RepairLog& log) {
    std::vector<std::uint32_t> neighbours;
    std::vector<Vec3> offered;
    std::vector<glm::vec3> startNormals;
    for (std::uint32_t v : verticesOf(mesh, suspects)) {
        neighboursOf(mesh, stars, v, neighbours);
        offered.clear();
        repair.candidates(v, neighbours, offered);
        if (offered.empty()) continue;
        const std::vector<std::uint32_t> ring = trianglesAround(stars, neighbours);
        auto place = [&](const Vec3& x) {
            mesh.vertices[v] = x;
            normal[v] = checkNormal(mesh, stars, v);
            for (std::uint32_t w : neighbours) normal[w] = checkNormal(mesh, stars, w);
            std::size_t n = 0;
            for (std::uint32_t t : ring) n += suspect(mesh, normal, t, repair.minCosine);
            return n;
        };
        const Vec3 start = mesh.vertices[v];
        const glm::vec3 startNormal = normal[v];
        startNormals.clear();
        for (std::uint32_t w : neighbours) startNormals.push_back(normal[w]);
        Vec3 best = start;
        std::size_t fewest = place(start);
        for (const Vec3& x : offered) {
            if (fewest == 0) break;
            const std::size_t n = place(x);
            if (n < fewest) fewest = n, best = x;
        }
        if (best != start) {
            log.position(v, start);
            log.normal(v, startNormal);
            for (std::size_t k = 0; k < neighbours.size(); ++k) log.normal(neighbours[k], startNormals[k]);
            suspects.insert(suspects.end(), ring.begin(), ring.end());
        }
        place(best);
    }
    sortUnique(suspects);
    keepSuspects(mesh, normal, repair.minCosine, suspects);
}

/// The local repair of repairAndCheckMesh: rounds of pulls on the suspects' vertices, testing again
/// only the triangles around moved vertices and their neighbours, then the candidates' last
/// resort. Leaves in `suspects` the triangles that are still suspect.
void pullBack(Mesh& mesh, const StarChunks& stars, Normals& normal, std::vector<std::uint32_t>& suspects,
              const FoldRepair& repair, RepairLog& log) {
    std::vector<std::uint32_t> neighbours;
    for (int round = 0; round < repair.rounds && !suspects.empty(); ++round) {
        std::vector<std::uint32_t> changed;
        for (std::uint32_t v : verticesOf(mesh, suspects)) {
            neighboursOf(mesh, stars, v, neighbours);
            const Vec3 before = mesh.vertices[v];
            if (!repair.pull(v, round, mesh.vertices[v], neighbours)) continue;
            changed.push_back(v);
            log.position(v, before);
        }
        if (changed.empty()) break;
        // The normals that moved: the moved vertices' and their neighbours'.
        const std::vector<std::uint32_t> touched = verticesOf(mesh, trianglesAround(stars, changed));
        for (std::uint32_t w : touched) {
            log.normal(w, normal[w]);
            normal[w] = checkNormal(mesh, stars, w);
        }
        // The triangles whose test may have changed: those around any touched vertex; and the
        // suspects no pull touched, which must not be forgotten.
        std::vector<std::uint32_t> again = trianglesAround(stars, touched);
        again.insert(again.end(), suspects.begin(), suspects.end());
        sortUnique(again);
        keepSuspects(mesh, normal, repair.minCosine, again);
        suspects.swap(again);
    }
    if (!suspects.empty() && repair.candidates) tryCandidates(mesh, stars, normal, suspects, repair, log);
}

/// Whether triangle t faces against its vertices' area-weighted normals and is not degenerate.
bool facesAgainst(const Mesh& mesh, const Normals& normal, std::uint32_t t) {
    const Mesh::Triangle& tri = mesh.triangles[t];
    const Facing f = facingOf(tri, mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]], normal);
    return !f.degenerate && f.facing < 0.0;
}

/// The triangles of `triangles` that face against their vertices' area-weighted normals.
std::vector<std::uint32_t> facingAgainstAmong(const Mesh& mesh, const Normals& normal,
                                              const std::vector<std::uint32_t>& triangles) {
    std::vector<std::uint32_t> out;
    for (std::uint32_t t : triangles)
        if (facesAgainst(mesh, normal, t)) out.push_back(t);
    return out;
}

/// Every triangle of the mesh that faces against its vertices' area-weighted normals, in order.
std::vector<std::uint32_t> facingAgainstAll(const Mesh& mesh, const Normals& normal) {
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 8192), std::vector<std::uint32_t>{},
        [&](const tbb::blocked_range<std::size_t>& rt, std::vector<std::uint32_t> found) {
            for (std::size_t t = rt.begin(); t < rt.end(); ++t)
                if (facesAgainst(mesh, normal, std::uint32_t(t))) found.push_back(std::uint32_t(t));
            return found;
        },
        [](std::vector<std::uint32_t> a, const std::vector<std::uint32_t>& b) {
            a.insert(a.end(), b.begin(), b.end());
            return a;
        });
}

/// The folded triangles: those facing against their vertices' area-weighted normals (the repair's
/// test) that face against their angle-weighted normals too. On a ridge sharper than a right
/// angle the two weightings disagree: by area a vertex takes the normal of the ridge's larger
/// side, and the small triangles of the other side face against it though the surface does not
/// fold (on boat-xyzac.ngc with a D1 at h = 0.25, where a sheet thinner than the spacing only just
/// holds a lattice point, the corner triangle round it, 0.007 h across, against its crossings'
/// normals, which the sheet's far side, a thousand times larger, set); by angle (Thurmer and
/// Wuthrich, "Computing vertex normals from polygonal facets", 1998) the small triangles count as
/// much as the large ones. Only triangles the area test flags are tried, so the angle weights
/// are summed at their vertices alone, from their stars: a mesh with no such triangle costs
/// nothing more. `suspects` holds every triangle the area test flags (with others) when
/// `flagged`, the count of those, matches; the whole mesh is scanned for them otherwise.
std::size_t foldedByAngleToo(const Mesh& mesh, const StarChunks& stars, const Normals& normal,
                             const std::vector<std::uint32_t>& suspects, std::size_t flagged) {
    std::vector<std::uint32_t> facingAgainst = facingAgainstAmong(mesh, normal, suspects);
    if (facingAgainst.size() != flagged) facingAgainst = facingAgainstAll(mesh, normal);
    const std::vector<std::uint32_t> vertices = verticesOf(mesh, facingAgainst);
    std::vector<Vec3> byAngle(vertices.size(), Vec3(0.0));
    // Corner `corner`'s triangle's unit normal times its angle there, added to its vertex's sum k.
    const auto addCorner = [&](std::size_t k, std::uint32_t corner) {
        const CornerSides c = cornerSides(mesh, corner);
        const Vec3& pv = mesh.vertices[vertices[k]];
        const Vec3 out = mesh.vertices[c.out] - pv, in = mesh.vertices[c.in] - pv;
        const Vec3 area = glm::cross(out, in);
        const double twiceArea = glm::length(area);
        if (twiceArea > 0.0) byAngle[k] += area * (std::atan2(twiceArea, glm::dot(out, in)) / twiceArea);
    };
    for (std::size_t k = 0; k < vertices.size(); ++k)
        for (const std::uint32_t* c = stars.begin(vertices[k]); c != stars.end(vertices[k]); ++c) addCorner(k, *c);
    const auto unitAt = [&](std::uint32_t v) {
        const Vec3& sum = byAngle[std::size_t(std::lower_bound(vertices.begin(), vertices.end(), v) - vertices.begin())];
        const double l = glm::length(sum);
        return l > 0.0 ? sum / l : Vec3(0.0);
    };
    std::size_t folded = 0;
    for (const std::uint32_t t : facingAgainst) {
        const Mesh::Triangle& tri = mesh.triangles[t];
        const Vec3 area = glm::cross(mesh.vertices[tri[1]] - mesh.vertices[tri[0]],
                                     mesh.vertices[tri[2]] - mesh.vertices[tri[0]]);
        folded += glm::dot(area, unitAt(tri[0]) + unitAt(tri[1]) + unitAt(tri[2])) < 0.0;
    }
    return folded;
}

MeshCheck check(Mesh* repairable, const Mesh& mesh, const FoldRepair* repair, std::size_t* moved,
                std::vector<std::uint32_t>* unrepaired) {
    MeshCheck r;
    r.vertexCount = mesh.vertices.size();
    r.triangleCount = mesh.triangles.size();
    const std::size_t nv = mesh.vertices.size();
    for (const Mesh::Triangle& t : mesh.triangles)
        if (t[0] >= nv || t[1] >= nv || t[2] >= nv) ++r.invalidIndices;
    if (r.invalidIndices > 0) return r;

    const StarChunks stars(mesh);
    Normals normal;
    const VertexCounts v = vertexPass(mesh, stars, normal);
    r.edgeCount = v.edges;
    r.boundaryEdges = v.boundary;
    r.nonManifoldEdges = v.nonManifold;
    r.misorientedEdges = v.misoriented;
    r.unusedVertices = v.unused;
    // The volume about the bounding-box centre, so that far-off parts do not lose digits.
    const Vec3 centre = mesh.vertices.empty() ? Vec3(0.0) : mesh.bounds().center();
    TriangleCounts t = trianglePass(mesh, normal, centre, repair ? repair->minCosine : 0.0);
    if (!repair && unrepaired) {
        std::sort(t.suspects.begin(), t.suspects.end());
        *unrepaired = t.suspects;
    }
    if (repair && !t.suspects.empty()) {
        std::sort(t.suspects.begin(), t.suspects.end());
        RepairLog log(mesh.vertices.size());
        pullBack(*repairable, stars, normal, t.suspects, *repair, log);
        if (moved) *moved = log.positions.size();
        if (unrepaired) *unrepaired = t.suspects;
        // Vertices moved, the topology did not: the edge counts stand, and only the triangles
        // around renormalised vertices (a superset of those around moved ones) changed. Their
        // sums are taken out as they were and put back as they are.
        std::vector<std::uint32_t> renormalised;
        for (const auto& [w, old] : log.normals) renormalised.push_back(w);
        const std::vector<std::uint32_t> affected = trianglesAround(stars, renormalised);
        const TriangleCounts now = triangleSums(mesh, normal, centre, affected);
        auto swapLogged = [&] {
            for (auto& [v, old] : log.positions) std::swap(repairable->vertices[v], old);
            for (auto& [w, old] : log.normals) std::swap(normal[w], old);
        };
        swapLogged();  // back to the state before the repair
        const TriangleCounts before = triangleSums(mesh, normal, centre, affected);
        swapLogged();
        t.degenerate = t.degenerate - before.degenerate + now.degenerate;
        t.folded = t.folded - before.folded + now.folded;
        t.area = t.area - before.area + now.area;
        t.volume6 = t.volume6 - before.volume6 + now.volume6;
    }
    r.degenerateTriangles = t.degenerate;
    r.facingAgainstTriangles = t.folded;
    r.foldedTriangles = t.folded == 0 ? 0 : foldedByAngleToo(mesh, stars, normal, t.suspects, t.folded);
    r.area = t.area;
    r.signedVolume = t.volume6 / 6.0;
    return r;
}

}  // namespace

std::string MeshCheck::openness() const {
    std::string out;
    const auto add = [&](std::size_t n, const char* what) {
        if (n == 0) return;
        out += (out.empty() ? "" : ", ") + std::to_string(n) + what;
    };
    add(boundaryEdges, boundaryEdges == 1 ? " edge on one triangle" : " edges on one triangle");
    add(nonManifoldEdges, nonManifoldEdges == 1 ? " edge on three or more" : " edges on three or more");
    add(misorientedEdges, misorientedEdges == 1 ? " edge used twice the same way" : " edges used twice the same way");
    add(invalidIndices, invalidIndices == 1 ? " triangle past the vertex list" : " triangles past the vertex list");
    if (triangleCount == 0) out = "no triangles";
    return out;
}

MeshCheck checkMesh(const Mesh& mesh, std::vector<std::uint32_t>* folded) {
    if (folded) folded->clear();
    return check(nullptr, mesh, nullptr, nullptr, folded);
}

MeshCheck repairAndCheckMesh(Mesh& mesh, const FoldRepair& repair, std::size_t* moved,
                             std::vector<std::uint32_t>* unrepaired) {
    if (moved) *moved = 0;
    if (unrepaired) unrepaired->clear();
    return check(&mesh, mesh, &repair, moved, unrepaired);
}

struct FoldWatch::State {
    const Mesh& mesh;
    Stars stars;
    Normals normal;
    std::vector<char> suspect;  ///< per triangle: check's suspect test with no margin
    /// Per vertex and per triangle, the update that last took it in (0: none): no sorting.
    std::vector<std::uint32_t> vertexSeen, triangleSeen;
    std::uint32_t update = 0;

    explicit State(const Mesh& m) : mesh(m), stars(detail::buildStars(m)) {}
};

FoldWatch::FoldWatch(const Mesh& mesh) : s_(std::make_unique<State>(mesh)) {
    State& s = *s_;
    const std::size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
    detail::reservePopulated(s.normal, nv);
    s.normal.resize(nv);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t v = r.begin(); v < r.end(); ++v) s.normal[v] = checkNormal(mesh, s.stars, v);
    });
    s.suspect.resize(nt);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 8192), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t t = r.begin(); t < r.end(); ++t) s.suspect[t] = suspect(mesh, s.normal, std::uint32_t(t), 0.0);
    });
    s.vertexSeen.assign(nv, 0);
    s.triangleSeen.assign(nt, 0);
}

FoldWatch::~FoldWatch() = default;

void FoldWatch::moved(const std::vector<std::uint32_t>& vertices) {
    State& s = *s_;
    const std::uint32_t u = ++s.update;
    // The vertices whose normals may change: the moved ones and their neighbours.
    std::vector<std::uint32_t> renormal;
    for (std::uint32_t v : vertices)
        for (const std::uint32_t* c = s.stars.begin(v); c != s.stars.end(v); ++c)
            for (std::uint32_t w : s.mesh.triangles[*c / 3])
                if (s.vertexSeen[w] != u) s.vertexSeen[w] = u, renormal.push_back(w);
    // The triangles whose test may change: those around any of them.
    std::vector<std::uint32_t> retest;
    for (std::uint32_t w : renormal)
        for (const std::uint32_t* c = s.stars.begin(w); c != s.stars.end(w); ++c) {
            const std::uint32_t t = *c / 3;
            if (s.triangleSeen[t] != u) s.triangleSeen[t] = u, retest.push_back(t);
        }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, renormal.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t k = r.begin(); k < r.end(); ++k)
                              s.normal[renormal[k]] = checkNormal(s.mesh, s.stars, renormal[k]);
                      });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, retest.size(), 2048),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t k = r.begin(); k < r.end(); ++k)
                              s.suspect[retest[k]] = suspect(s.mesh, s.normal, retest[k], 0.0);
                      });
}

std::vector<std::uint32_t> FoldWatch::folded() const {
    std::vector<std::uint32_t> out;
    for (std::size_t t = 0; t < s_->suspect.size(); ++t)
        if (s_->suspect[t]) out.push_back(std::uint32_t(t));
    return out;
}

}  // namespace dexelmill
