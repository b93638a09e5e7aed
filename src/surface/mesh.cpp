#include "dexelmill/surface/mesh.h"

#include <algorithm>
#include <cmath>

#include <atomic>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

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

/// Sorts a short range in place (stars hold a handful of entries).
template <class T>
void insertionSort(T* first, T* last) {
    for (T* i = first + 1; i < last; ++i)
        for (T* j = i; j > first && *j < *(j - 1); --j) std::swap(*j, *(j - 1));
}

/// Every vertex's star: the triangle corners at it, as 3 t + k for corner k of triangle t, grouped
/// by vertex (offsets into `corners`) and sorted within each vertex, so that sums over a star come
/// out the same for any thread count.
struct Stars {
    std::vector<std::uint32_t> offset;
    std::vector<std::uint32_t> corners;
};

Stars buildStars(const Mesh& mesh) {
    const std::size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
    Stars s;
    s.offset.assign(nv + 1, 0);
    if (tbb::this_task_arena::max_concurrency() == 1) {
        // A counting sort in triangle order: each star comes out sorted, without atomics.
        for (const Mesh::Triangle& t : mesh.triangles)
            for (std::uint32_t v : t) ++s.offset[v + 1];
        for (std::size_t v = 0; v < nv; ++v) s.offset[v + 1] += s.offset[v];
        s.corners.resize(s.offset[nv]);
        std::vector<std::uint32_t> cursor(s.offset.begin(), s.offset.end() - 1);
        for (std::size_t t = 0; t < nt; ++t)
            for (int k = 0; k < 3; ++k) s.corners[cursor[mesh.triangles[t][k]]++] = std::uint32_t(3 * t + k);
        return s;
    }
    // In parallel: counted and filled with atomic cursors, then each star sorted.
    std::vector<std::atomic<std::uint32_t>> count(nv);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 8192), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t t = r.begin(); t < r.end(); ++t)
            for (std::uint32_t v : mesh.triangles[t]) count[v].fetch_add(1, std::memory_order_relaxed);
    });
    for (std::size_t v = 0; v < nv; ++v) {
        s.offset[v + 1] = s.offset[v] + count[v].load(std::memory_order_relaxed);
        count[v].store(s.offset[v], std::memory_order_relaxed);
    }
    s.corners.resize(s.offset[nv]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 8192), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t t = r.begin(); t < r.end(); ++t)
            for (int k = 0; k < 3; ++k)
                s.corners[count[mesh.triangles[t][k]].fetch_add(1, std::memory_order_relaxed)] = std::uint32_t(3 * t + k);
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t v = r.begin(); v < r.end(); ++v)
            insertionSort(s.corners.data() + s.offset[v], s.corners.data() + s.offset[v + 1]);
    });
    return s;
}

/// What the pass over the vertices finds.
struct VertexCounts {
    std::size_t edges = 0, boundary = 0, nonManifold = 0, misoriented = 0, unused = 0;
};

/// One pass over the vertices' stars: the edge counts, and each vertex's unit normal (the
/// area-weighted mean direction of its triangles; zero without area around it).
///
/// Every edge at a vertex v shows in v's own star: triangle (v, a, b) walks v -> a and b -> v.
/// Per vertex, the edges to each neighbour w > v are counted by direction (each undirected edge
/// once, at its smaller end): used once it is a boundary edge; more than twice, non-manifold;
/// twice in one direction, misoriented.
VertexCounts vertexPass(const Mesh& mesh, const Stars& stars, std::vector<glm::vec3>& normal) {
    const std::size_t nv = mesh.vertices.size();
    normal.assign(nv, glm::vec3(0.0f));
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, nv, 4096), VertexCounts{},
        [&](const tbb::blocked_range<std::size_t>& rv, VertexCounts c) {
            constexpr int kNext[3] = {1, 2, 0}, kPrev[3] = {2, 0, 1};
            std::vector<std::uint64_t> around;  // (neighbour << 1) | (1 for v -> w, 0 for w -> v)
            for (std::size_t v = rv.begin(); v < rv.end(); ++v) {
                const std::uint32_t lo = stars.offset[v], hi = stars.offset[v + 1];
                c.unused += lo == hi;
                around.resize(2 * std::size_t(hi - lo));
                std::size_t n = 0;
                Vec3 sum(0.0);
                const Vec3& pv = mesh.vertices[v];
                for (std::uint32_t i = lo; i < hi; ++i) {
                    const std::uint32_t corner = stars.corners[i];
                    const Mesh::Triangle& t = mesh.triangles[corner / 3];
                    const int k = int(corner % 3);
                    const std::uint32_t out = t[kNext[k]], in = t[kPrev[k]];
                    // The area vector from this corner: the same for each of its corners.
                    sum += glm::cross(mesh.vertices[out] - pv, mesh.vertices[in] - pv);
                    if (out > v) around[n++] = (std::uint64_t(out) << 1) | 1u;
                    if (in > v) around[n++] = std::uint64_t(in) << 1;
                }
                around.resize(n);
                const double l = glm::length(sum);
                if (l > 0.0) normal[v] = glm::vec3(sum / l);
                insertionSort(around.data(), around.data() + n);
                for (std::size_t i = 0; i < around.size();) {
                    std::size_t j = i, forward = 0;
                    while (j < around.size() && (around[j] >> 1) == (around[i] >> 1)) forward += around[j++] & 1u;
                    const std::size_t uses = j - i;
                    ++c.edges;
                    if (uses == 1) ++c.boundary;
                    else if (uses > 2) ++c.nonManifold;
                    else if (forward != 1) ++c.misoriented;
                    i = j;
                }
            }
            return c;
        },
        [](VertexCounts a, const VertexCounts& b) {
            a.edges += b.edges, a.boundary += b.boundary, a.nonManifold += b.nonManifold;
            a.misoriented += b.misoriented, a.unused += b.unused;
            return a;
        });
}

/// What the pass over the triangles finds.
struct TriangleCounts {
    std::size_t degenerate = 0;
    double area = 0.0, volume6 = 0.0;
    std::vector<std::uint32_t> folded;
};

/// One pass over the triangles: degenerate ones, area, six times the enclosed volume (about
/// `centre`), and the folded ones (facing against the sum of their vertices' unit normals).
/// Ranges are reduced in a fixed order, so the sums do not depend on the thread count.
TriangleCounts trianglePass(const Mesh& mesh, const std::vector<glm::vec3>& normal, const Vec3& centre,
                            double minCosine = 0.0) {
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 8192), TriangleCounts{},
        [&](const tbb::blocked_range<std::size_t>& rt, TriangleCounts c) {
            for (std::size_t t = rt.begin(); t < rt.end(); ++t) {
                const Mesh::Triangle& tri = mesh.triangles[t];
                const Vec3& a = mesh.vertices[tri[0]];
                const Vec3& b = mesh.vertices[tri[1]];
                const Vec3& d = mesh.vertices[tri[2]];
                c.volume6 += glm::dot(a - centre, glm::cross(b - centre, d - centre));
                if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) {
                    ++c.degenerate;
                    if (minCosine > 0.0) c.folded.push_back(std::uint32_t(t));
                    continue;
                }
                const Vec3 areaVector = glm::cross(b - a, d - a);
                const double twiceArea = glm::length(areaVector);
                const double longest2 = std::max({glm::dot(b - a, b - a), glm::dot(d - b, d - b), glm::dot(a - d, a - d)});
                if (!(twiceArea > tol::kDegenerateTriangle * longest2)) {
                    ++c.degenerate;
                    if (minCosine > 0.0) c.folded.push_back(std::uint32_t(t));
                    continue;
                }
                c.area += 0.5 * twiceArea;
                const Vec3 sum = Vec3(normal[tri[0]]) + Vec3(normal[tri[1]]) + Vec3(normal[tri[2]]);
                const double facing = glm::dot(areaVector, sum);
                if (facing < 0.0 || (minCosine > 0.0 && facing < minCosine * twiceArea * glm::length(sum)))
                    c.folded.push_back(std::uint32_t(t));
            }
            return c;
        },
        [](TriangleCounts a, const TriangleCounts& b) {
            a.degenerate += b.degenerate;
            a.area += b.area;
            a.volume6 += b.volume6;
            a.folded.insert(a.folded.end(), b.folded.begin(), b.folded.end());
            return a;
        });
}

bool validIndices(const Mesh& mesh) {
    const std::size_t nv = mesh.vertices.size();
    for (const Mesh::Triangle& t : mesh.triangles)
        if (t[0] >= nv || t[1] >= nv || t[2] >= nv) return false;
    return true;
}

}  // namespace

std::vector<std::uint32_t> foldedTriangles(const Mesh& mesh, double minCosine) {
    if (!validIndices(mesh)) return {};
    std::vector<glm::vec3> normal;
    vertexPass(mesh, buildStars(mesh), normal);
    return trianglePass(mesh, normal, Vec3(0.0), minCosine).folded;
}

MeshCheck checkMesh(const Mesh& mesh) {
    std::vector<std::uint32_t> unused;
    return checkMesh(mesh, 0.0, unused);
}

MeshCheck checkMesh(const Mesh& mesh, double minCosine, std::vector<std::uint32_t>& nearlyFolded) {
    nearlyFolded.clear();
    MeshCheck r;
    r.vertexCount = mesh.vertices.size();
    r.triangleCount = mesh.triangles.size();
    const std::size_t nv = mesh.vertices.size();
    for (const Mesh::Triangle& t : mesh.triangles)
        if (t[0] >= nv || t[1] >= nv || t[2] >= nv) ++r.invalidIndices;
    if (r.invalidIndices > 0) return r;

    std::vector<glm::vec3> normal;
    const VertexCounts v = vertexPass(mesh, buildStars(mesh), normal);
    r.edgeCount = v.edges;
    r.boundaryEdges = v.boundary;
    r.nonManifoldEdges = v.nonManifold;
    r.misorientedEdges = v.misoriented;
    r.unusedVertices = v.unused;
    // The volume about the bounding-box centre, so that far-off parts do not lose digits.
    const Vec3 centre = mesh.vertices.empty() ? Vec3(0.0) : mesh.bounds().center();
    TriangleCounts t = trianglePass(mesh, normal, centre, minCosine);
    r.degenerateTriangles = t.degenerate;
    r.area = t.area;
    r.signedVolume = t.volume6 / 6.0;
    std::sort(t.folded.begin(), t.folded.end());
    r.foldedTriangles = minCosine > 0.0 ? trianglePass(mesh, normal, centre).folded.size() : t.folded.size();
    nearlyFolded = std::move(t.folded);
    return r;
}

}  // namespace dexelmill
