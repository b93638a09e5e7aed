// Exact point-to-mesh distance: a bounding-volume hierarchy with closed-form closest points.
#include "dexelmill/compare/mesh_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "dexelmill/geometry/tolerance.h"

namespace dexelmill {

namespace {

/// Leaves hold at most this many triangles: small enough that a leaf's box is tight, large enough
/// that the hierarchy stays shallow.
constexpr std::uint32_t kLeafTriangles = 4;

/// The closest point of segment [a, b] to p (a point when a == b).
Vec3 closestOnSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
    const Vec3 ab = b - a;
    const double len2 = glm::dot(ab, ab);
    if (!(len2 > 0.0)) return a;
    const double t = std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0);
    return a + t * ab;
}

/// Squared distance from p to a box (0 inside).
double boxDistance2(const Box& box, const Vec3& p) {
    const Vec3 d = glm::max(glm::max(box.lo - p, p - box.hi), Vec3(0.0));
    return glm::dot(d, d);
}

}  // namespace

Vec3 closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    // A degenerate triangle (checkMesh's measure: doubled area at most kDegenerateTriangle times
    // the longest squared edge) is taken as its three edges; the face it drops is at most that
    // fraction of its longest edge wide.
    const double longest2 = std::max({glm::dot(ab, ab), glm::dot(ac, ac), glm::dot(c - b, c - b)});
    if (glm::length(glm::cross(ab, ac)) <= tol::kDegenerateTriangle * longest2) {
        Vec3 best = closestOnSegment(p, a, b);
        for (const Vec3& q : {closestOnSegment(p, b, c), closestOnSegment(p, a, c)})
            if (glm::dot(q - p, q - p) < glm::dot(best - p, best - p)) best = q;
        return best;
    }
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    // The region of vertex a.
    if (d1 <= 0.0 && d2 <= 0.0) return a;
    const Vec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    // The region of vertex b.
    if (d3 >= 0.0 && d4 <= d3) return b;
    const Vec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    // The region of vertex c.
    if (d6 >= 0.0 && d5 <= d6) return c;
    // vc, vb and va are the barycentric weights of c, b and a, scaled by twice the area squared;
    // a negative one puts p beyond the edge opposite that vertex.
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return closestOnSegment(p, a, b);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return closestOnSegment(p, a, c);
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) return closestOnSegment(p, b, c);
    const double sum = va + vb + vc;
    return a + ab * (vb / sum) + ac * (vc / sum);
}

MeshDistance::MeshDistance(const Mesh& mesh) {
    const std::size_t n = mesh.triangles.size();
    if (n == 0) return;
    // Triangles in Morton order of their centroids (21 bits per axis), so that halving a range
    // of them halves space; the hierarchy splits ranges at their middle, and its boxes are
    // gathered bottom-up. Any split gives exact answers; this one keeps boxes tight and the build
    // at one sort.
    std::vector<Vec3> centroid(n);
    Box all;
    for (std::size_t t = 0; t < n; ++t) {
        const auto& tri = mesh.triangles[t];
        centroid[t] = (mesh.vertices[tri[0]] + mesh.vertices[tri[1]] + mesh.vertices[tri[2]]) / 3.0;
        all.expand(centroid[t]);
    }
    const Vec3 size = glm::max(all.size(), Vec3(1e-300));
    auto spread = [](std::uint64_t v) {
        v &= 0x1fffff;
        v = (v | v << 32) & 0x1f00000000ffffULL;
        v = (v | v << 16) & 0x1f0000ff0000ffULL;
        v = (v | v << 8) & 0x100f00f00f00f00fULL;
        v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
        v = (v | v << 2) & 0x1249249249249249ULL;
        return v;
    };
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n);
    for (std::size_t t = 0; t < n; ++t) {
        const Vec3 u = (centroid[t] - all.lo) / size * double((1u << 21) - 1);
        keyed[t] = {spread(std::uint64_t(u.x)) | spread(std::uint64_t(u.y)) << 1 | spread(std::uint64_t(u.z)) << 2,
                    std::uint32_t(t)};
    }
    std::sort(keyed.begin(), keyed.end());
    original_.resize(n);
    corners_.resize(3 * n);
    slot_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        original_[i] = keyed[i].second;
        slot_[keyed[i].second] = std::uint32_t(i);
        for (int k = 0; k < 3; ++k)
            corners_[3 * i + std::size_t(k)] = mesh.vertices[mesh.triangles[keyed[i].second][std::size_t(k)]];
    }
    // Ranges split at their middle; a child always comes after its parent.
    nodes_.reserve(2 * (n / kLeafTriangles + 1));
    struct Job {
        std::uint32_t node, begin, end;
    };
    std::vector<Job> jobs{{0u, 0u, std::uint32_t(n)}};
    nodes_.emplace_back();
    while (!jobs.empty()) {
        const Job job = jobs.back();
        jobs.pop_back();
        if (job.end - job.begin <= kLeafTriangles) {
            nodes_[job.node].first = job.begin;
            nodes_[job.node].count = job.end - job.begin;
            for (std::uint32_t i = 3 * job.begin; i < 3 * job.end; ++i) nodes_[job.node].box.expand(corners_[i]);
            continue;
        }
        const std::uint32_t mid = job.begin + (job.end - job.begin) / 2;
        const std::uint32_t left = std::uint32_t(nodes_.size());
        nodes_.emplace_back();
        nodes_.emplace_back();
        nodes_[job.node].first = left;
        nodes_[job.node].count = 0;
        jobs.push_back({left, job.begin, mid});
        jobs.push_back({left + 1, mid, job.end});
    }
    for (std::size_t k = nodes_.size(); k-- > 0;) {
        Node& node = nodes_[k];
        if (node.count > 0) continue;
        node.box = nodes_[node.first].box;
        node.box.expand(nodes_[node.first + 1].box);
    }
}

double MeshDistance::distanceTo(const Vec3& p, std::uint32_t triangle) const {
    const std::size_t i = slot_.at(triangle);
    return glm::length(closestPointOnTriangle(p, corners_[3 * i], corners_[3 * i + 1], corners_[3 * i + 2]) - p);
}

MeshDistance::Nearest MeshDistance::nearest(const Vec3& p) const {
    Nearest best;
    best.distance = std::numeric_limits<double>::infinity();
    if (nodes_.empty()) return best;
    double best2 = std::numeric_limits<double>::infinity();
    // Depth-first, nearer child first; a node whose box is no nearer than the best triangle so far
    // holds nothing nearer, so the answer is the exact minimum over all triangles.
    struct Entry {
        std::uint32_t node;
        double d2;
    };
    Entry stack[128];
    int top = 0;
    stack[top++] = {0u, boxDistance2(nodes_[0].box, p)};
    while (top > 0) {
        const Entry e = stack[--top];
        if (e.d2 >= best2) continue;
        const Node& node = nodes_[e.node];
        if (node.count > 0) {
            for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
                const Vec3 q = closestPointOnTriangle(p, corners_[3 * i], corners_[3 * i + 1], corners_[3 * i + 2]);
                const double d2 = glm::dot(q - p, q - p);
                if (d2 < best2) {
                    best2 = d2;
                    best.point = q;
                    best.triangle = original_[i];
                }
            }
            continue;
        }
        const double dl = boxDistance2(nodes_[node.first].box, p);
        const double dr = boxDistance2(nodes_[node.first + 1].box, p);
        // The median split halves every range, so the depth is below 33 for 2^32 triangles and
        // the stack holds at most one pending sibling per level.
        if (dl <= dr) {
            stack[top++] = {node.first + 1, dr};
            stack[top++] = {node.first, dl};
        } else {
            stack[top++] = {node.first, dl};
            stack[top++] = {node.first + 1, dr};
        }
    }
    best.distance = std::sqrt(best2);
    return best;
}

}  // namespace dexelmill
