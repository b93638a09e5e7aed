#include "dexelmill/surface/mesh.h"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_sort.h>

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
    // that far-off parts do not lose digits.
    const Vec3 c = mesh.vertices.empty() ? Vec3(0.0) : mesh.bounds().center();
    double v6 = 0.0;
    for (const Mesh::Triangle& t : mesh.triangles) {
        const Vec3 a = mesh.vertices[t[0]] - c, b = mesh.vertices[t[1]] - c,
                   d = mesh.vertices[t[2]] - c;
        v6 += glm::dot(a, glm::cross(b, d));
    }
    return v6 / 6.0;
}

namespace {

/// An undirected edge (lo, hi) and whether the triangle walked it from lo to hi.
struct EdgeUse {
    std::uint64_t key;
    bool forward;
};

}  // namespace

MeshCheck checkMesh(const Mesh& mesh) {
    MeshCheck r;
    r.vertexCount = mesh.vertices.size();
    r.triangleCount = mesh.triangles.size();
    const std::size_t nv = mesh.vertices.size();

    std::vector<EdgeUse> uses;
    uses.reserve(3 * mesh.triangles.size());
    std::vector<bool> used(nv, false);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Mesh::Triangle& tri = mesh.triangles[t];
        if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv) {
            ++r.invalidIndices;
            continue;
        }
        for (std::uint32_t i : tri) used[i] = true;
        if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) {
            ++r.degenerateTriangles;
        } else {
            const Vec3& a = mesh.vertices[tri[0]];
            const Vec3& b = mesh.vertices[tri[1]];
            const Vec3& c = mesh.vertices[tri[2]];
            const double twiceArea = glm::length(glm::cross(b - a, c - a));
            const double longest2 = std::max({glm::dot(b - a, b - a), glm::dot(c - b, c - b),
                                              glm::dot(a - c, a - c)});
            if (!(twiceArea > tol::kDegenerateTriangle * longest2)) ++r.degenerateTriangles;
            r.area += 0.5 * twiceArea;
        }
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t p = tri[e], q = tri[(e + 1) % 3];
            if (p == q) continue;
            const std::uint64_t lo = std::min(p, q), hi = std::max(p, q);
            uses.push_back({(lo << 32) | hi, p < q});
        }
    }
    r.unusedVertices = std::size_t(std::count(used.begin(), used.end(), false));

    tbb::parallel_sort(uses.begin(), uses.end(),
                       [](const EdgeUse& x, const EdgeUse& y) { return x.key < y.key; });
    for (std::size_t i = 0; i < uses.size();) {
        std::size_t j = i, forward = 0;
        while (j < uses.size() && uses[j].key == uses[i].key) forward += uses[j++].forward;
        const std::size_t n = j - i;
        ++r.edgeCount;
        if (n == 1) {
            ++r.boundaryEdges;
        } else if (n > 2) {
            ++r.nonManifoldEdges;
        } else if (forward != 1) {
            ++r.misorientedEdges;
        }
        i = j;
    }
    if (r.invalidIndices == 0) r.signedVolume = meshVolume(mesh);
    return r;
}

}  // namespace dexelmill
