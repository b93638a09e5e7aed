#include "dexelmill/surface/simplify.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

#include "dexelmill/geometry/tolerance.h"

namespace dexelmill {

namespace {

constexpr std::uint32_t kNoStar = std::numeric_limits<std::uint32_t>::max();

/// Edge collapses on a closed mesh: the stars (triangles around) of the vertices that may take
/// part, the link condition, and the mesh compacted at the end.
class Collapser {
public:
    /// Stars of every vertex, or, with `tracked`, of the vertices it flags.
    Collapser(Mesh& mesh, const std::vector<char>* tracked)
        : mesh_(mesh), slot_(mesh.vertices.size(), kNoStar), alive_(mesh.triangles.size(), true) {
        for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v)
            if (!tracked || (*tracked)[v]) slot_[v] = std::uint32_t(around_.size()), around_.emplace_back();
        for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
            for (std::uint32_t v : mesh.triangles[t])
                if (slot_[v] != kNoStar) around_[slot_[v]].push_back(t);
    }

    const Mesh& mesh() const { return mesh_; }
    /// The triangles around u (a tracked vertex); empty once u has been collapsed away.
    const std::vector<std::uint32_t>& star(std::uint32_t u) const { return around_[slot_[u]]; }

    /// The vertices joined to u by an edge, sorted.
    std::vector<std::uint32_t> neighbours(std::uint32_t u) const {
        std::vector<std::uint32_t> out;
        for (std::uint32_t t : star(u))
            for (std::uint32_t w : mesh_.triangles[t])
                if (w != u) out.push_back(w);
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
        return out;
    }

    /// The two triangles on edge u-v, when the vertices next to both u and v (`nu`: u's
    /// neighbours) are exactly the two across it (the link condition of Dey et al. 1999), which
    /// keeps a closed 2-manifold closed and manifold; false otherwise.
    bool linked(std::uint32_t u, std::uint32_t v, const std::vector<std::uint32_t>& nu,
                std::array<std::uint32_t, 2>& shared) const {
        std::vector<std::uint32_t> opposite;
        std::size_t found = 0;
        for (std::uint32_t t : star(u)) {
            const Mesh::Triangle& tri = mesh_.triangles[t];
            if (tri[0] != v && tri[1] != v && tri[2] != v) continue;
            if (found == 2) return false;
            shared[found++] = t;
            for (std::uint32_t w : tri)
                if (w != u && w != v) opposite.push_back(w);
        }
        if (found != 2) return false;
        std::sort(opposite.begin(), opposite.end());
        const std::vector<std::uint32_t> nv = neighbours(v);
        std::vector<std::uint32_t> common;
        std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(), std::back_inserter(common));
        return common == opposite;
    }

    /// Triangle t of u's star with v in u's place.
    Mesh::Triangle moved(std::uint32_t t, std::uint32_t u, std::uint32_t v) const {
        Mesh::Triangle tri = mesh_.triangles[t];
        for (std::uint32_t& w : tri)
            if (w == u) w = v;
        return tri;
    }

    /// Twice the area vector of `tri`, or zero where it is degenerate against its longest edge.
    Vec3 areaUnlessDegenerate(const Mesh::Triangle& tri) const {
        const Vec3& a = mesh_.vertices[tri[0]];
        const Vec3 area = glm::cross(mesh_.vertices[tri[1]] - a, mesh_.vertices[tri[2]] - a);
        double longest2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const Vec3 e = mesh_.vertices[tri[(k + 1) % 3]] - mesh_.vertices[tri[k]];
            longest2 = std::max(longest2, glm::dot(e, e));
        }
        return glm::length(area) > tol::kDegenerateTriangle * longest2 ? area : Vec3(0.0);
    }

    /// Collapses u into v (which keeps its place): drops the two triangles on their edge and hands
    /// u's others to v (tracked too).
    void collapse(std::uint32_t u, std::uint32_t v, const std::array<std::uint32_t, 2>& shared) {
        for (std::uint32_t t : shared) {
            alive_[t] = false;
            for (std::uint32_t w : mesh_.triangles[t]) {
                if (slot_[w] == kNoStar) continue;
                auto& list = around_[slot_[w]];
                list.erase(std::remove(list.begin(), list.end(), t), list.end());
            }
        }
        auto& from = around_[slot_[u]];
        for (std::uint32_t t : from) {
            for (std::uint32_t& w : mesh_.triangles[t])
                if (w == u) w = v;
            around_[slot_[v]].push_back(t);
        }
        from.clear();
    }

    /// Drops the collapsed triangles and the vertices no triangle uses any more, in place: the
    /// vertices kept keep their order, so a list never needs a second copy.
    void compact() {
        std::vector<std::uint32_t> remap(mesh_.vertices.size(), kNoStar);
        std::size_t kept = 0;
        for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
            if (!alive_[t]) continue;
            for (std::uint32_t w : mesh_.triangles[t]) remap[w] = 0;
            mesh_.triangles[kept++] = mesh_.triangles[t];
        }
        mesh_.triangles.resize(kept);
        std::uint32_t next = 0;
        for (std::size_t v = 0; v < mesh_.vertices.size(); ++v) {
            if (remap[v] == kNoStar) continue;
            remap[v] = next;
            mesh_.vertices[next++] = mesh_.vertices[v];
        }
        mesh_.vertices.resize(next);
        for (Mesh::Triangle& tri : mesh_.triangles)
            for (std::uint32_t& w : tri) w = remap[w];
    }

private:
    Mesh& mesh_;
    std::vector<std::uint32_t> slot_;  ///< vertex -> its star in around_, or kNoStar
    std::vector<std::vector<std::uint32_t>> around_;
    std::vector<bool> alive_;
};

Vec3 unit(const Vec3& v) {
    const double l = glm::length(v);
    return l > 0.0 ? v / l : Vec3(0.0);
}

class FlatMerger {
public:
    FlatMerger(Mesh& mesh, const FlatMergeOptions& options)
        : c_(mesh, nullptr), cosAngle_(std::cos(options.maxAngle)), maxDistance_(options.maxDistance) {}

    std::size_t run() {
        std::size_t merged = 0;
        for (bool again = true; again;) {
            again = false;
            for (std::uint32_t u = 0; u < c_.mesh().vertices.size(); ++u) {
                if (c_.star(u).empty()) continue;
                if (tryMerge(u)) {
                    ++merged;
                    again = true;
                }
            }
        }
        c_.compact();
        return merged;
    }

private:
    bool tryMerge(std::uint32_t u) {
        const Mesh& mesh = c_.mesh();
        // Flat around u: every triangle within the angle of the mean normal.
        Vec3 mean(0.0);
        for (std::uint32_t t : c_.star(u)) mean += mesh.areaVector(t);
        mean = unit(mean);
        if (mean == Vec3(0.0)) return false;
        for (std::uint32_t t : c_.star(u))
            if (!(glm::dot(unit(mesh.areaVector(t)), mean) >= cosAngle_)) return false;
        const std::vector<std::uint32_t> nu = c_.neighbours(u);
        const Vec3& pu = mesh.vertices[u];
        // Try the nearest neighbours first.
        std::vector<std::uint32_t> order = nu;
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
            const double da = glm::dot(mesh.vertices[a] - pu, mesh.vertices[a] - pu);
            const double db = glm::dot(mesh.vertices[b] - pu, mesh.vertices[b] - pu);
            return da < db || (da == db && a < b);
        });
        for (std::uint32_t v : order)
            if (collapse(u, v, nu, mean)) return true;
        return false;
    }

    bool collapse(std::uint32_t u, std::uint32_t v, const std::vector<std::uint32_t>& nu, const Vec3& mean) {
        std::array<std::uint32_t, 2> shared{};
        if (!c_.linked(u, v, nu, shared)) return false;
        // The triangles u leaves, with v in its place: flat, not degenerate, and near u.
        const Mesh& mesh = c_.mesh();
        const Vec3& pu = mesh.vertices[u];
        for (std::uint32_t t : c_.star(u)) {
            if (t == shared[0] || t == shared[1]) continue;
            const Mesh::Triangle tri = c_.moved(t, u, v);
            const Vec3 n = unit(c_.areaUnlessDegenerate(tri));
            if (n == Vec3(0.0)) return false;
            if (!(glm::dot(n, mean) >= cosAngle_)) return false;
            if (!(std::abs(glm::dot(n, pu - mesh.vertices[tri[0]])) <= maxDistance_)) return false;
        }
        c_.collapse(u, v, shared);
        return true;
    }

    Collapser c_;
    double cosAngle_, maxDistance_;
};

}  // namespace

std::size_t mergeFlatRegions(Mesh& mesh, const FlatMergeOptions& options) {
    if (!(options.maxAngle > 0.0) && !(options.maxDistance > 0.0)) return 0;
    return FlatMerger(mesh, options).run();
}

std::size_t collapseShortEdges(Mesh& mesh, double length) {
    if (!(length > 0.0)) return 0;
    // The short edges, shortest first, each once (from the triangle it runs down the indices in)
    // as its newer end u and older end v.
    struct Edge {
        double length2;
        std::uint32_t u, v;
    };
    std::vector<Edge> edges;
    for (const Mesh::Triangle& tri : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = tri[std::size_t(k)], b = tri[std::size_t((k + 1) % 3)];
            const Vec3 d = mesh.vertices[a] - mesh.vertices[b];
            if (a > b && glm::dot(d, d) < length * length) edges.push_back({glm::dot(d, d), a, b});
        }
    if (edges.empty()) return 0;
    std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
        return std::tie(x.length2, x.u, x.v) < std::tie(y.length2, y.u, y.v);
    });
    // A collapse changes the stars of its ends and of their neighbours, so their normals: those
    // stars are kept, and every vertex's normal (checkMesh's: the unit sum of its triangles' area
    // vectors), to test the triangles round them for folds before the collapse is made.
    std::vector<char> ends(mesh.vertices.size(), 0), tracked(mesh.vertices.size(), 0);
    for (const Edge& e : edges) ends[e.u] = ends[e.v] = 1;
    for (const Mesh::Triangle& tri : mesh.triangles)
        if (ends[tri[0]] || ends[tri[1]] || ends[tri[2]]) tracked[tri[0]] = tracked[tri[1]] = tracked[tri[2]] = 1;
    std::vector<Vec3> normal(mesh.vertices.size(), Vec3(0.0));
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        for (std::uint32_t w : mesh.triangles[t]) normal[w] += mesh.areaVector(t);
    for (Vec3& n : normal) n = unit(n);
    Collapser c(mesh, &tracked);
    const auto area = [&](const Mesh::Triangle& tri) {
        return glm::cross(mesh.vertices[tri[1]] - mesh.vertices[tri[0]], mesh.vertices[tri[2]] - mesh.vertices[tri[0]]);
    };
    std::vector<char> tookIn(mesh.vertices.size(), 0);  // a vertex that took another in stays
    std::vector<std::uint32_t> near;
    std::vector<Vec3> nearNormal;
    const auto tryCollapse = [&](std::uint32_t u, std::uint32_t v) {
        // An end already collapsed away has handed its triangles on; its edges are gone.
        if (c.star(u).empty() || c.star(v).empty() || tookIn[u]) return false;
        const std::vector<std::uint32_t> nu = c.neighbours(u);
        if (!std::binary_search(nu.begin(), nu.end(), v)) return false;
        std::array<std::uint32_t, 2> shared{};
        if (!c.linked(u, v, nu, shared)) return false;
        const auto kept = [&](std::uint32_t t) { return t != shared[0] && t != shared[1]; };
        // v and the ends' neighbours get new stars: their normals after the collapse.
        near = nu;
        const std::vector<std::uint32_t> nv = c.neighbours(v);
        near.insert(near.end(), nv.begin(), nv.end());
        std::sort(near.begin(), near.end());
        near.erase(std::unique(near.begin(), near.end()), near.end());
        near.erase(std::remove(near.begin(), near.end(), u), near.end());
        nearNormal.assign(near.size(), Vec3(0.0));
        for (std::size_t i = 0; i < near.size(); ++i) {
            for (std::uint32_t t : c.star(near[i]))
                if (kept(t)) nearNormal[i] += area(c.moved(t, u, v));
            if (near[i] == v)
                for (std::uint32_t t : c.star(u)) {
                    if (!kept(t)) continue;
                    const Mesh::Triangle tri = c.moved(t, u, v);
                    if (c.areaUnlessDegenerate(tri) == Vec3(0.0)) return false;
                    nearNormal[i] += area(tri);
                }
            nearNormal[i] = unit(nearNormal[i]);
        }
        const auto normalAfter = [&](std::uint32_t w) {
            const auto it = std::lower_bound(near.begin(), near.end(), w);
            return it != near.end() && *it == w ? nearNormal[std::size_t(it - near.begin())] : normal[w];
        };
        // No triangle round them may come to face against its corners' normals (checkMesh's
        // fold); one that did already (a crumple's next to it) is that one's to mend.
        const auto folded = [](const Vec3& a, const Vec3& n) { return glm::dot(a, n) < 0.0; };
        for (std::size_t i = 0; i < near.size(); ++i)
            for (const std::vector<std::uint32_t>* star : {&c.star(near[i]), near[i] == v ? &c.star(u) : nullptr}) {
                if (!star) continue;
                for (std::uint32_t t : *star) {
                    if (!kept(t)) continue;
                    const Mesh::Triangle& was = mesh.triangles[t];
                    const Mesh::Triangle tri = c.moved(t, u, v);
                    if (folded(area(tri), normalAfter(tri[0]) + normalAfter(tri[1]) + normalAfter(tri[2])) &&
                        !folded(area(was), normal[was[0]] + normal[was[1]] + normal[was[2]]))
                        return false;
                }
            }
        c.collapse(u, v, shared);
        tookIn[v] = 1;
        for (std::size_t i = 0; i < near.size(); ++i) normal[near[i]] = nearNormal[i];
        return true;
    };
    // A collapse refused for a fold that a crumple next to it made may be made once that one is
    // gone: passes until one collapses nothing.
    std::size_t collapsed = 0;
    for (std::size_t pass = std::size_t(-1); pass != 0;) {
        pass = 0;
        for (const Edge& e : edges) pass += tryCollapse(e.u, e.v) ? 1 : 0;
        collapsed += pass;
    }
    c.compact();
    return collapsed;
}

}  // namespace dexelmill
