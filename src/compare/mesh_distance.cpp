// Exact point-to-mesh distance: a bounding-volume hierarchy with closed-form closest points.
#include "dexelmill/compare/mesh_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"
#include "memory/pages.h"

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

/// Directions for the inside test's rays: the fractional parts of the square roots of the first
/// eighteen primes, three by three, with signs, made unit; far from the axes and every plane of
/// small integer normal, so that no ray runs along the faces machined and designed parts are full
/// of. The first decides almost always; the others serve when a ray meets an edge.
constexpr double kRays[][3] = {{0.47413860622660531, 0.83795795482700841, 0.27022036937956673},
                               {-0.68683798550132802, 0.33677040904332112, 0.64408017611573143},
                               {0.13963054079120774, -0.40707525204102657, 0.9026588786768176},
                               {-0.55735713455199754, -0.82158990776427432, -0.11976246500418172},
                               {0.36717645145138433, 0.50773007487449717, -0.77935333743271218},
                               {-0.25581872022143476, 0.62207669265655807, -0.73998470986753861}};

/// A ray's meeting with a triangle within this fraction (of the barycentric weights, or of the
/// triangle's size along the ray) of a boundary does not count: another ray is tried. Double
/// rounding of the weights is about 1e-15 relative, far below it.
constexpr double kRayMargin = 1e-9;

/// How far behind a shell's largest triangle, as a fraction of its longest edge, the point lies
/// that tells which way the shell faces: far above the rays' margin, far below any wall's
/// thickness a mesher keeps.
constexpr double kProbeDepth = 1e-6;

enum class Crossing { None, One, Ambiguous };

/// Whether the ray p + t d, t > 0, crosses triangle (a, b, c) (Moller-Trumbore).
Crossing crossing(const Vec3& p, const Vec3& d, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 e1 = b - a, e2 = c - a;
    const Vec3 q = glm::cross(d, e2);
    // det = -d . (e1 x e2): the cosine of the ray's angle with the normal, times twice the area.
    const double det = glm::dot(e1, q);
    const double nn = glm::length(glm::cross(e1, e2));
    if (!(nn > 0.0)) return Crossing::None;  // a degenerate triangle bounds no volume
    const double size = std::max(glm::length(e1), glm::length(e2));
    if (!(std::abs(det) > kRayMargin * nn)) {
        // The ray runs (nearly) along the triangle's plane: it crosses nothing unless it starts
        // on that plane near the triangle, which another ray settles.
        return std::abs(glm::dot(p - a, glm::cross(e1, e2))) > kRayMargin * nn * size ? Crossing::None
                                                                                       : Crossing::Ambiguous;
    }
    const Vec3 s = p - a;
    const double u = glm::dot(s, q) / det;
    if (u < -kRayMargin || u > 1.0 + kRayMargin) return Crossing::None;
    const Vec3 r = glm::cross(s, e1);
    const double v = glm::dot(d, r) / det;
    if (v < -kRayMargin || u + v > 1.0 + kRayMargin) return Crossing::None;
    const double t = glm::dot(e2, r) / det;
    if (t < -kRayMargin * size) return Crossing::None;
    if (u < kRayMargin || v < kRayMargin || u + v > 1.0 - kRayMargin || t < kRayMargin * size)
        return Crossing::Ambiguous;
    return Crossing::One;
}

/// Whether the ray p + t d, t >= 0, meets the box (slab test; inv = 1 / d componentwise).
bool rayMeetsBox(const Box& box, const Vec3& p, const Vec3& inv) {
    double lo = 0.0, hi = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
        double t0 = (box.lo[k] - p[k]) * inv[k], t1 = (box.hi[k] - p[k]) * inv[k];
        if (t0 > t1) std::swap(t0, t1);
        lo = std::max(lo, t0);
        hi = std::min(hi, t1);
    }
    return lo <= hi;
}

/// The nodes of the hierarchy over m triangles: ranges split at their middle until a leaf holds
/// at most kLeafTriangles.
std::size_t nodeCount(std::size_t m) {
    return m <= kLeafTriangles ? 1 : 1 + nodeCount(m / 2) + nodeCount(m - m / 2);
}

/// Whether every edge of the mesh is shared by exactly two triangles that run it in opposite
/// directions (a closed, consistently oriented 2-manifold, shell by shell); if so, `shell`
/// receives each triangle's shell (connected by edges), numbered from 0 in the order of their
/// first triangles. The half-edges are listed by the vertex they leave: each half-edge a -> b must
/// be the only one from a to b, and b's list must hold exactly one b -> a, whose triangle joins
/// its shell.
bool pairedEdges(const Mesh& mesh, std::vector<std::uint32_t>& shell) {
    const std::size_t n = mesh.triangles.size(), vertices = mesh.vertices.size();
    if (vertices >= (std::size_t(1) << 32) - 1) return false;
    std::vector<std::uint32_t> start(vertices + 1, 0);
    for (const Mesh::Triangle& tri : mesh.triangles)
        for (std::size_t k = 0; k < 3; ++k) {
            if (tri[k] == tri[(k + 1) % 3] || tri[k] >= vertices) return false;
            ++start[tri[k] + 1];
        }
    for (std::size_t v = 0; v < vertices; ++v) start[v + 1] += start[v];
    struct HalfEdge {
        std::uint32_t to, triangle;
    };
    std::vector<HalfEdge, NoZeroAllocator<HalfEdge>> out;
    detail::reservePopulated(out, 3 * n);
    out.resize(3 * n);
    {
        std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
        for (std::size_t t = 0; t < n; ++t)
            for (std::size_t k = 0; k < 3; ++k)
                out[next[mesh.triangles[t][k]]++] = {mesh.triangles[t][(k + 1) % 3], std::uint32_t(t)};
    }
    // Each vertex's list sorted by the vertex reached, so that a repeat sits next to its twin
    // and the way back is a binary search, however many triangles meet at a vertex.
    auto less = [](const HalfEdge& x, const HalfEdge& y) { return x.to < y.to; };
    tbb::parallel_for(std::size_t(0), vertices,
                      [&](std::size_t v) { std::sort(out.begin() + start[v], out.begin() + start[v + 1], less); });
    std::vector<std::uint32_t> parent(n);
    for (std::size_t t = 0; t < n; ++t) parent[t] = std::uint32_t(t);
    auto find = [&](std::uint32_t t) {
        while (parent[t] != t) t = parent[t] = parent[parent[t]];
        return t;
    };
    for (std::uint32_t a = 0; a < vertices; ++a)
        for (std::uint32_t i = start[a]; i < start[a + 1]; ++i) {
            const std::uint32_t b = out[i].to;
            if ((i > start[a] && out[i - 1].to == b) || (i + 1 < start[a + 1] && out[i + 1].to == b)) return false;
            const auto first = out.begin() + start[b], last = out.begin() + start[b + 1];
            const auto back = std::lower_bound(first, last, HalfEdge{a, 0}, less);
            if (back == last || back->to != a || (back + 1 != last && (back + 1)->to == a)) return false;
            const std::uint32_t r0 = find(out[i].triangle), r1 = find(back->triangle);
            if (r0 != r1) parent[std::max(r0, r1)] = std::min(r0, r1);
        }
    shell.assign(n, 0);
    std::vector<std::uint32_t> number(n, std::uint32_t(-1));
    std::uint32_t shells = 0;
    for (std::size_t t = 0; t < n; ++t) {
        const std::uint32_t r = find(std::uint32_t(t));
        if (number[r] == std::uint32_t(-1)) number[r] = shells++;
        shell[t] = number[r];
    }
    return true;
}

/// The closest point of a triangle, and whether it lies inside the face rather than on an edge or
/// a corner.
struct Closest {
    Vec3 point;
    bool onFace = false;
};

Closest closestOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, bc = c - b, ca = a - c;
    const Vec3 n = glm::cross(ab, -ca);
    const double n2 = glm::dot(n, n);
    // A degenerate triangle (checkMesh's measure: doubled area at most kDegenerateTriangle times
    // the longest squared edge) is taken as its three edges; the face it drops is at most that
    // fraction of its longest edge wide.
    const double longest2 = std::max({glm::dot(ab, ab), glm::dot(bc, bc), glm::dot(ca, ca)});
    const Vec3 edges[3][2] = {{a, b}, {b, c}, {c, a}};
    const auto onEdges = [&](const bool (&beyond)[3]) {
        Vec3 best(0.0);
        double best2 = std::numeric_limits<double>::infinity();
        for (int k = 0; k < 3; ++k) {
            if (!beyond[k]) continue;
            const Vec3 q = closestOnSegment(p, edges[k][0], edges[k][1]);
            if (glm::dot(q - p, q - p) < best2) best = q, best2 = glm::dot(q - p, q - p);
        }
        return best;
    };
    if (std::sqrt(n2) <= tol::kDegenerateTriangle * longest2) return {onEdges({true, true, true}), false};
    // A corner whose two edges both lead away from p (each dot product as accurate as its terms)
    // is the closest point: most triangles a search tries are met so.
    const Vec3 ap = p - a, bp = p - b, cp = p - c;
    if (glm::dot(ab, ap) <= 0.0 && glm::dot(ca, ap) >= 0.0) return {a, false};
    if (glm::dot(bc, bp) <= 0.0 && glm::dot(ab, bp) >= 0.0) return {b, false};
    if (glm::dot(ca, cp) <= 0.0 && glm::dot(bc, cp) >= 0.0) return {c, false};
    // p's foot on the plane, found directly: the normal's direction is good to some eps L / h
    // rounding units, so the foot to about eps |p - a| L / h. Barycentric weights from products of dot products (Ericson's regions) cancel in a thin
    // triangle, by about (L / h)^2 rounding units for one h high and L long: points on triangles
    // 1e-5 as high as long, 100 mm from the origin, came out up to 0.55 um off them. Where the
    // foot lies within every edge it is the closest point. Elsewhere the closest point lies on an
    // edge p is beyond (the normal cone at a vertex is spanned by its two edges' normals), so only
    // those are tried. An edge test that rounds the wrong way takes a foot within rounding (some
    // eps |p - a|) of that edge's line, so either answer is within that of the other.
    const bool beyond[3] = {glm::dot(glm::cross(ab, ap), n) < 0.0, glm::dot(glm::cross(bc, bp), n) < 0.0,
                            glm::dot(glm::cross(ca, cp), n) < 0.0};
    if (!beyond[0] && !beyond[1] && !beyond[2]) return {p - n * (glm::dot(n, ap) / n2), true};
    return {onEdges(beyond), false};
}

}  // namespace

Vec3 closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    return closestOnTriangle(p, a, b, c).point;
}

MeshDistance::MeshDistance(const Mesh& mesh, bool orient) {
    const std::size_t n = mesh.triangles.size();
    if (n == 0) return;

    // Triangles in Morton order of their centroids (21 bits per axis), so that halving a range
    // of them halves space; the hierarchy splits ranges at their middle, and its boxes are
    // gathered bottom-up. Any split gives exact answers; this one keeps boxes tight and the build
    // at one sort.
    auto centroid = [&](std::size_t t) {
        const auto& tri = mesh.triangles[t];
        return (mesh.vertices[tri[0]] + mesh.vertices[tri[1]] + mesh.vertices[tri[2]]) / 3.0;
    };
    const Box all = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n), Box{},
        [&](const tbb::blocked_range<std::size_t>& r, Box box) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) box.expand(centroid(i));
            return box;
        },
        [](Box x, const Box& y) {
            x.expand(y);
            return x;
        });
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
    std::vector<std::pair<std::uint64_t, std::uint32_t>, NoZeroAllocator<std::pair<std::uint64_t, std::uint32_t>>> keyed;
    detail::reservePopulated(keyed, n);
    keyed.resize(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
        const Vec3 u = (centroid(i) - all.lo) / size * double((1u << 21) - 1);
        keyed[i] = {spread(std::uint64_t(u.x)) | spread(std::uint64_t(u.y)) << 1 | spread(std::uint64_t(u.z)) << 2,
                    std::uint32_t(i)};
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    detail::reservePopulated(original_, n);
    detail::reservePopulated(slot_, n);
    original_.resize(n);
    slot_.resize(n);
    const bool single = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, mesh.vertices.size()), true,
        [&](const tbb::blocked_range<std::size_t>& r, bool all) {
            for (std::size_t v = r.begin(); all && v != r.end(); ++v) all = Vec3(glm::vec3(mesh.vertices[v])) == mesh.vertices[v];
            return all;
        },
        [](bool x, bool y) { return x && y; });
    if (single) {
        detail::reservePopulated(single_, 3 * n);
        single_.resize(3 * n);
    } else {
        detail::reservePopulated(corners_, 3 * n);
        corners_.resize(3 * n);
    }
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
        original_[i] = keyed[i].second;
        slot_[keyed[i].second] = std::uint32_t(i);
        for (std::size_t k = 0; k < 3; ++k) {
            const Vec3& v = mesh.vertices[mesh.triangles[keyed[i].second][k]];
            if (single)
                single_[3 * i + k] = glm::vec3(v);
            else
                corners_[3 * i + k] = v;
        }
    });
    // Ranges split at their middle; a child always comes after its parent.
    // Median splits leave leaves of at least kLeafTriangles / 2 triangles. The nodes are counted
    // first, so that their pages are faulted in at once.
    detail::reservePopulated(nodes_, nodeCount(n));
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
    tbb::parallel_for(std::size_t(0), nodes_.size(), [&](std::size_t k) {
        Node& node = nodes_[k];
        for (std::size_t i = 3 * std::size_t(node.first); node.count > 0 && i < 3 * std::size_t(node.first + node.count); ++i)
            node.box.expand(corner(i));
    });
    for (std::size_t k = nodes_.size(); k-- > 0;) {
        Node& node = nodes_[k];
        if (node.count > 0) continue;
        node.box = nodes_[node.first].box;
        node.box.expand(nodes_[node.first + 1].box);
    }
    if (orient) orientation_ = orientationOf(mesh);
}

int MeshDistance::orientationOf(const Mesh& mesh) const {
    std::vector<std::uint32_t> shell;
    if (!pairedEdges(mesh, shell)) return 0;
    // Each shell faces one way throughout; which way, a point just behind its largest triangle
    // tells: inside the solid (by the rays' parity, which ignores orientation) when the shell
    // faces out. A shell may bound a cavity, so its own volume's sign would not do.
    const std::uint32_t shells = *std::max_element(shell.begin(), shell.end()) + 1;
    std::vector<std::uint32_t> largest(shells, 0);
    std::vector<double> area2(shells, -1.0);
    for (std::size_t t = 0; t < shell.size(); ++t) {
        const double a2 = glm::length(mesh.areaVector(t));
        if (a2 > area2[shell[t]]) area2[shell[t]] = a2, largest[shell[t]] = std::uint32_t(t);
    }
    int facing = 0;
    for (std::uint32_t k = 0; k < shells; ++k) {
        const Mesh::Triangle& tri = mesh.triangles[largest[k]];
        const Vec3 &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
        const Vec3 n = mesh.areaVector(largest[k]);
        if (!(area2[k] > 0.0)) return 0;
        const double size = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
        const Vec3 behind = (a + b + c) / 3.0 - kProbeDepth * size * (n / area2[k]);
        const int way = inside(behind) ? 1 : -1;
        if (facing != 0 && way != facing) return 0;
        facing = way;
    }
    return facing;
}

double MeshDistance::distanceTo(const Vec3& p, std::uint32_t triangle) const {
    const std::size_t i = slot_.at(triangle);
    return glm::length(closestPointOnTriangle(p, corner(3 * i), corner(3 * i + 1), corner(3 * i + 2)) - p);
}

bool MeshDistance::inside(const Vec3& p) const {
    if (nodes_.empty()) return false;
    for (const auto& ray : kRays) {
        const Vec3 d(ray[0], ray[1], ray[2]);
        const Vec3 inv = 1.0 / d;  // no component is zero
        bool odd = false, ambiguous = false;
        std::uint32_t stack[128];
        int top = 0;
        stack[top++] = 0;
        while (top > 0 && !ambiguous) {
            const Node& node = nodes_[stack[--top]];
            if (!rayMeetsBox(node.box, p, inv)) continue;
            if (node.count == 0) {
                stack[top++] = node.first;
                stack[top++] = node.first + 1;
                continue;
            }
            for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
                const Crossing c = crossing(p, d, corner(3 * i), corner(3 * i + 1), corner(3 * i + 2));
                if (c == Crossing::Ambiguous) ambiguous = true;
                if (c == Crossing::One) odd = !odd;
            }
        }
        if (!ambiguous) return odd;
    }
    return false;
}

double MeshDistance::signedDistance(const Vec3& p, std::uint32_t* hint) const {
    if (nodes_.empty()) return std::numeric_limits<double>::infinity();
    const Found f = search(p, hint);
    if (hint) *hint = original_[f.slot];
    return withSign(p, f);
}

double MeshDistance::withSign(const Vec3& p, const Found& f) const {
    const double d = std::sqrt(f.d2);
    if (!(d > 0.0)) return d;
    if (orientation_ != 0 && f.onFace) {
        const Vec3 a = corner(3 * f.slot), b = corner(3 * f.slot + 1), c = corner(3 * f.slot + 2);
        const double side = glm::dot(p - f.point, glm::cross(b - a, c - a)) * orientation_;
        return side < 0.0 ? -d : d;
    }
    return inside(p) ? -d : d;
}

bool MeshDistance::slotsNear(const Vec3& c, double radius, std::size_t limit, std::vector<std::uint32_t>& out) const {
    out.clear();
    if (nodes_.empty()) return true;
    const double r2 = radius * radius;
    std::uint32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& node = nodes_[stack[--top]];
        if (boxDistance2(node.box, c) > r2) continue;
        if (node.count == 0) {
            stack[top++] = node.first;
            stack[top++] = node.first + 1;
            continue;
        }
        for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
            const Vec3 q = closestPointOnTriangle(c, corner(3 * i), corner(3 * i + 1), corner(3 * i + 2));
            if (glm::dot(q - c, q - c) > r2) continue;
            if (out.size() == limit) return false;
            out.push_back(i);
        }
    }
    return true;
}

double MeshDistance::signedDistanceAmong(const Vec3& p, const std::vector<std::uint32_t>& slots) const {
    Found best;
    best.d2 = std::numeric_limits<double>::infinity();
    for (std::uint32_t i : slots) {
        const Closest c = closestOnTriangle(p, corner(3 * i), corner(3 * i + 1), corner(3 * i + 2));
        const double d2 = glm::dot(c.point - p, c.point - p);
        if (d2 < best.d2) best = {i, d2, c.point, c.onFace, true};
    }
    if (!best.found) return std::numeric_limits<double>::infinity();
    return withSign(p, best);
}

MeshDistance::Found MeshDistance::search(const Vec3& p, const std::uint32_t* hint) const {
    Found best;
    best.d2 = std::numeric_limits<double>::infinity();
    auto test = [&](std::uint32_t i) {
        const Closest c = closestOnTriangle(p, corner(3 * i), corner(3 * i + 1), corner(3 * i + 2));
        const double d2 = glm::dot(c.point - p, c.point - p);
        if (d2 < best.d2) best = {i, d2, c.point, c.onFace, true};
    };
    // The hint's triangle bounds the search from the start.
    if (hint && *hint < slot_.size()) test(slot_[*hint]);
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
        if (e.d2 >= best.d2) continue;
        const Node& node = nodes_[e.node];
        if (node.count > 0) {
            for (std::uint32_t i = node.first; i < node.first + node.count; ++i) test(i);
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
    return best;
}

MeshDistance::Nearest MeshDistance::nearest(const Vec3& p, std::uint32_t* hint) const {
    Nearest n;
    n.distance = std::numeric_limits<double>::infinity();
    if (nodes_.empty()) return n;
    const Found f = search(p, hint);
    n.distance = std::sqrt(f.d2);
    n.point = f.point;
    n.triangle = original_[f.slot];
    if (hint) *hint = n.triangle;
    return n;
}

}  // namespace dexelmill
