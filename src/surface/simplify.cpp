#include "dexelmill/surface/simplify.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "dexelmill/geometry/tolerance.h"

namespace dexelmill {

namespace {

class FlatMerger {
public:
    FlatMerger(Mesh& mesh, const FlatMergeOptions& options)
        : mesh_(mesh), cosAngle_(std::cos(options.maxAngle)), maxDistance_(options.maxDistance),
          around_(mesh.vertices.size()), alive_(mesh.triangles.size(), true) {
        for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
            for (std::uint32_t v : mesh.triangles[t]) around_[v].push_back(t);
    }

    std::size_t run() {
        std::size_t merged = 0;
        for (bool again = true; again;) {
            again = false;
            for (std::uint32_t u = 0; u < mesh_.vertices.size(); ++u) {
                if (around_[u].empty()) continue;
                if (tryMerge(u)) {
                    ++merged;
                    again = true;
                }
            }
        }
        compact();
        return merged;
    }

private:
    Vec3 unitNormal(const Mesh::Triangle& t) const {
        const Vec3 n = glm::cross(mesh_.vertices[t[1]] - mesh_.vertices[t[0]], mesh_.vertices[t[2]] - mesh_.vertices[t[0]]);
        const double l = glm::length(n);
        return l > 0.0 ? n / l : Vec3(0.0);
    }

    /// The vertices joined to u by an edge, sorted.
    std::vector<std::uint32_t> neighbours(std::uint32_t u) const {
        std::vector<std::uint32_t> out;
        for (std::uint32_t t : around_[u])
            for (std::uint32_t w : mesh_.triangles[t])
                if (w != u) out.push_back(w);
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
        return out;
    }

    bool tryMerge(std::uint32_t u) {
        // Flat around u: every triangle within the angle of the mean normal.
        Vec3 mean(0.0);
        for (std::uint32_t t : around_[u]) mean += mesh_.areaVector(t);
        const double ml = glm::length(mean);
        if (!(ml > 0.0)) return false;
        mean /= ml;
        for (std::uint32_t t : around_[u])
            if (!(glm::dot(unitNormal(mesh_.triangles[t]), mean) >= cosAngle_)) return false;
        const std::vector<std::uint32_t> nu = neighbours(u);
        const Vec3& pu = mesh_.vertices[u];
        // Try the nearest neighbours first.
        std::vector<std::uint32_t> order = nu;
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
            const double da = glm::dot(mesh_.vertices[a] - pu, mesh_.vertices[a] - pu);
            const double db = glm::dot(mesh_.vertices[b] - pu, mesh_.vertices[b] - pu);
            return da < db || (da == db && a < b);
        });
        for (std::uint32_t v : order)
            if (collapse(u, v, nu, mean)) return true;
        return false;
    }

    bool collapse(std::uint32_t u, std::uint32_t v, const std::vector<std::uint32_t>& nu, const Vec3& mean) {
        // The triangles on edge u-v, and the link condition.
        std::vector<std::uint32_t> shared, opposite;
        for (std::uint32_t t : around_[u]) {
            const Mesh::Triangle& tri = mesh_.triangles[t];
            if (tri[0] != v && tri[1] != v && tri[2] != v) continue;
            shared.push_back(t);
            for (std::uint32_t w : tri)
                if (w != u && w != v) opposite.push_back(w);
        }
        if (shared.size() != 2) return false;
        std::sort(opposite.begin(), opposite.end());
        const std::vector<std::uint32_t> nv = neighbours(v);
        std::vector<std::uint32_t> common;
        std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(), std::back_inserter(common));
        if (common != opposite) return false;
        // The triangles u leaves, with v in its place: flat, not degenerate, and near u.
        const Vec3& pu = mesh_.vertices[u];
        for (std::uint32_t t : around_[u]) {
            if (t == shared[0] || t == shared[1]) continue;
            Mesh::Triangle tri = mesh_.triangles[t];
            for (std::uint32_t& w : tri)
                if (w == u) w = v;
            const Vec3& a = mesh_.vertices[tri[0]];
            const Vec3 area = glm::cross(mesh_.vertices[tri[1]] - a, mesh_.vertices[tri[2]] - a);
            const double twiceArea = glm::length(area);
            double longest2 = 0.0;
            for (int k = 0; k < 3; ++k) {
                const Vec3 e = mesh_.vertices[tri[(k + 1) % 3]] - mesh_.vertices[tri[k]];
                longest2 = std::max(longest2, glm::dot(e, e));
            }
            if (!(twiceArea > tol::kDegenerateTriangle * longest2)) return false;
            const Vec3 n = area / twiceArea;
            if (!(glm::dot(n, mean) >= cosAngle_)) return false;
            if (!(std::abs(glm::dot(n, pu - a)) <= maxDistance_)) return false;
        }
        // Collapse: drop the two triangles on the edge, hand u's others to v.
        for (std::uint32_t t : shared) {
            alive_[t] = false;
            for (std::uint32_t w : mesh_.triangles[t]) {
                auto& list = around_[w];
                list.erase(std::remove(list.begin(), list.end(), t), list.end());
            }
        }
        for (std::uint32_t t : around_[u]) {
            for (std::uint32_t& w : mesh_.triangles[t])
                if (w == u) w = v;
            around_[v].push_back(t);
        }
        around_[u].clear();
        return true;
    }

    void compact() {
        std::vector<std::uint32_t> remap(mesh_.vertices.size(), ~0u);
        decltype(mesh_.vertices) vertices;
        decltype(mesh_.triangles) triangles;
        for (std::uint32_t t = 0; t < mesh_.triangles.size(); ++t) {
            if (!alive_[t]) continue;
            Mesh::Triangle tri = mesh_.triangles[t];
            for (std::uint32_t& w : tri) {
                if (remap[w] == ~0u) {
                    remap[w] = std::uint32_t(vertices.size());
                    vertices.push_back(mesh_.vertices[w]);
                }
                w = remap[w];
            }
            triangles.push_back(tri);
        }
        mesh_.vertices = std::move(vertices);
        mesh_.triangles = std::move(triangles);
    }

    Mesh& mesh_;
    double cosAngle_, maxDistance_;
    std::vector<std::vector<std::uint32_t>> around_;
    std::vector<bool> alive_;
};

}  // namespace

std::size_t mergeFlatRegions(Mesh& mesh, const FlatMergeOptions& options) {
    if (!(options.maxAngle > 0.0) && !(options.maxDistance > 0.0)) return 0;
    return FlatMerger(mesh, options).run();
}

}  // namespace dexelmill
