#include "surface/detail/patch_vertex.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>


namespace dexelmill::detail {

namespace {

/// A crossing this far (in h) on the material side of another's tangent plane reveals a convex
/// crease. Well above the packed normals' error (1.3e-4 rad over at most sqrt(3) h: 2.3e-4 h), so
/// a smooth concave patch never shows one.
constexpr double kConvexGap = 1e-3;

/// A smooth patch's vertex leaves the loop's mass point along the mean normal only as far as keeps
/// each fan triangle within this angle of that normal. Its crossing normals lie within half the
/// feature angle of the mean, so a fan triangle steeper than this cannot follow the surface; where
/// the loop is a sliver (two crossings a micrometre apart near one lattice point), the least-squares
/// offset would otherwise stand two fan triangles on edge over it. Kept as its squared tangent.
constexpr double kMaxFanTiltTan2 = 3.0;  // tan^2(60 degrees)

/// The offset s, nearest `wanted`, of the vertex mass + s n at which every fan triangle that is
/// within 60 degrees of n at s = 0 stays so. The fan triangle over crossings p, q has area
/// vector A0 - s (n x e), with A0 = (p - m) x (q - m) and e = q - p; its component along n is
/// A0 . n whatever s is, so the bound |A0_perp - s (n x e)|^2 <= kMaxFanTiltTan2 (A0 . n)^2 is
/// a quadratic in s whose solutions form an interval about 0. The result lies in all of them.
double fanOffset(const PatchVertexRule::Loop& loop, const Vec3& mass, const Vec3& n, double wanted) {
    // Per fan triangle that bounds s: |perp - s w|^2 <= kMaxFanTiltTan2 along^2, that is
    // a s^2 - 2 b s + c <= 0.
    double qa[PatchVertexRule::kMaxPlanes], qb[PatchVertexRule::kMaxPlanes], qc[PatchVertexRule::kMaxPlanes];
    int bounds = 0;
    bool holds = true;  // every bound holds at `wanted`, as it does for most patches
    for (int i = 0; i < loop.len; ++i) {
        const Vec3 p = loop.points[loop.index[i]] - mass;
        const Vec3 q = loop.points[loop.index[i + 1 == loop.len ? 0 : i + 1]] - mass;
        const Vec3 a0 = glm::cross(p, q);
        const double along = glm::dot(a0, n);
        const Vec3 perp = a0 - along * n;
        const Vec3 w = glm::cross(n, q - p);
        const double a = glm::dot(w, w), b = glm::dot(perp, w);
        const double c = glm::dot(perp, perp) - kMaxFanTiltTan2 * along * along;
        if (!(along > 0.0) || !(c <= 0.0) || !(a > 0.0)) continue;  // steep already, or s moves nothing
        qa[bounds] = a, qb[bounds] = b, qc[bounds] = c;
        ++bounds;
        holds = holds && (a * wanted - 2.0 * b) * wanted + c <= 0.0;
    }
    if (holds) return wanted;
    double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
    for (int k = 0; k < bounds; ++k) {
        const double root = std::sqrt(qb[k] * qb[k] - qa[k] * qc[k]);  // real: c <= 0
        lo = std::max(lo, (qb[k] - root) / qa[k]);
        hi = std::min(hi, (qb[k] + root) / qa[k]);
    }
    return std::clamp(wanted, lo, hi);
}

/// Whether a patch's crossings span a convex crease: one lies on the material side of
/// another's tangent plane (the normals point out of the material).
bool convexCrease(const PatchVertexRule::Loop& loop, double h) {
    const double gap = kConvexGap * h;
    for (int i = 0; i < loop.len; ++i) {
        const PackedNormal pn = loop.normals[loop.index[i]];
        if (!pn.present() || pn.sharp()) continue;
        const Vec3 n = pn.unpack();
        for (int j = 0; j < loop.len; ++j)
            if (j != i && glm::dot(n, loop.points[loop.index[j]] - loop.points[loop.index[i]]) < -gap) return true;
    }
    return false;
}

}  // namespace

PatchVertexRule::PatchVertexRule(double h, double featureAngle) : h_(h) {
    const double half = 0.5 * featureAngle;
    singular_ = std::tan(half) * std::tan(half);
    cosHalfFeature_ = std::cos(half);
}

Vec3 PatchVertexRule::massPoint(const Loop& loop) {
    Vec3 mass(0.0);
    for (int i = 0; i < loop.len; ++i) mass += loop.points[loop.index[i]];
    return mass / double(loop.len);
}

/// The vertex of a patch: where the tangent planes at its crossings meet best, within its
/// cell. Minimises sum_i (n_i . (x - p_i))^2 about the loop's mass point m by a truncated
/// SVD (the symmetric eigen-decomposition of A^T A): directions whose eigenvalue is below
/// tan^2(featureAngle / 2) times the largest are left at m. That keeps a smooth patch's
/// vertex on its mean plane, and puts an edge's on the crease line (rank 2) and a corner's on
/// the corner (rank 3). Crossings with no known normal, or marked sharp, add no plane.
///
/// Every machined surface is the stock's boundary minus convex swept volumes, so its smooth
/// pieces are concave (seen from the material) and its convex creases are where two cuts
/// meet. A concave crease is one cutter's own edge (a pocket's floor-wall corner, a V-groove's
/// bottom): its tangent planes are that cutter's faces, and their meeting point is exact. A
/// convex crease may be cut lower by a third cut between the crossings that no lattice edge
/// saw (a cusp next to a wall's top, say): there the vertex is kept within the box of its
/// crossings rather than extrapolated past them. A crease is convex when a crossing lies on
/// the material side of another's tangent plane (by more than kConvexGap h).
///
/// A patch that shares its cell with others keeps its vertex within the box of its crossings
/// too, whatever its rank: the fan then stays in that box, and fans whose boxes are apart cannot
/// pass through each other. Bounded by the whole cell, a vertex can land in another patch's part
/// of it. (helical-thread-milling.gcode from (0, 0, 0) at h = 0.1 mm, the cell at (-0.99, 1.20,
/// -0.97): a fin 0.06 h thick crosses the corner of the cell's z faces slantwise, and the face
/// rule saw its two ends as two stubs, two patches. The stub on the x = 1 edges, its crossings
/// 0.13 to 0.18 h up y, has a face vertex far across the face, off the fin; its least-squares
/// point, along the fin's slanting normal from that biased mass point, lay below y = 0 and was
/// clamped onto the y = 0 face, under the other stub, whose fan its own then crossed: 3388 pairs
/// of triangles in 154 such cells up the bore's wall.)
Vec3 PatchVertexRule::place(const Loop& loop, const Vec3& cellLo, bool sharesCell, int& rank) const {
    const Vec3 mass = massPoint(loop);
    rank = 0;
    if (loop.len > kMaxPlanes) return glm::clamp(mass, cellLo, cellLo + h_);
    Vec3 normal[kMaxPlanes], offset[kMaxPlanes];
    Vec3 mean(0.0);
    int planes = 0;
    for (int i = 0; i < loop.len; ++i) {
        const PackedNormal pn = loop.normals[loop.index[i]];
        if (!pn.present() || pn.sharp()) continue;
        normal[planes] = pn.unpack();
        offset[planes] = loop.points[loop.index[i]] - mass;
        mean += normal[planes++];
    }
    Vec3 v = mass;
    // A smooth patch: every normal within featureAngle / 2 of the mean. Then the second
    // eigenvalue of A^T A is at most tan^2(featureAngle / 2) times the first (on the plane
    // across the mean normal, sum (n_i . u)^2 <= k sin^2, while sum (n_i . mean)^2 >= k cos^2),
    // so the truncated SVD keeps rank 1; the least-squares point is taken along the mean normal
    // rather than the first eigenvector, without the eigen-decomposition.
    const double meanLength = glm::length(mean);
    bool smooth = planes > 0 && meanLength > 0.0;
    if (smooth) {
        mean /= meanLength;
        for (int i = 0; i < planes && smooth; ++i) smooth = glm::dot(normal[i], mean) >= cosHalfFeature_;
    }
    if (smooth) {
        double num = 0.0, den = 0.0;
        for (int i = 0; i < planes; ++i) {
            const double c = glm::dot(normal[i], mean);
            num += c * glm::dot(normal[i], offset[i]);
            den += c * c;
        }
        rank = 1;
        v = mass + mean * fanOffset(loop, mass, mean, num / den);
    } else if (planes > 0) {
        Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
        Eigen::Vector3d atb = Eigen::Vector3d::Zero();
        for (int i = 0; i < planes; ++i) {
            const Eigen::Vector3d n(normal[i].x, normal[i].y, normal[i].z);
            ata += n * n.transpose();
            atb += n * glm::dot(normal[i], offset[i]);
        }
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
        eig.computeDirect(ata);
        const Eigen::Vector3d w = eig.eigenvalues();
        const double wmax = w.maxCoeff();
        Eigen::Vector3d sol = Eigen::Vector3d::Zero();
        for (int k = 0; k < 3; ++k) {
            if (!(w[k] > singular_ * wmax)) continue;
            ++rank;
            const Eigen::Vector3d vk = eig.eigenvectors().col(k);
            sol += vk * (vk.dot(atb) / w[k]);
        }
        v = mass + Vec3(sol[0], sol[1], sol[2]);
    }
    Vec3 lo = cellLo;
    Vec3 hi = lo + h_;
    if (sharesCell || (rank >= 2 && convexCrease(loop, h_))) {
        // The box of the crossings (they lie on the cell's edges and faces, so inside the cell).
        lo = hi = loop.points[loop.index[0]];
        for (int i = 1; i < loop.len; ++i) {
            lo = glm::min(lo, loop.points[loop.index[i]]);
            hi = glm::max(hi, loop.points[loop.index[i]]);
        }
    }
    if (rank < 2) return glm::clamp(v, lo, hi);
    const double inset = kFaceInset * h_;
    return glm::clamp(glm::clamp(v, lo, hi), cellLo + inset, cellLo + (h_ - inset));
}

}  // namespace dexelmill::detail
