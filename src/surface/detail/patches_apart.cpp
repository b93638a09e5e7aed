#include "surface/detail/patches_apart.h"

#include <algorithm>
#include <array>

#include "surface/detail/crossings.h"

namespace dexelmill::detail {

namespace {

/// A vertex moved apart stands on its own side of the plane between the two loops at least this
/// share of the way from that plane to its loop's nearest crossing. Not none: on the plane, a
/// vertex rounded to float could cross it. Not more: the vertex moves off its fitted place only as
/// far as it must.
constexpr double kOwnSide = 0.25;

/// The search for the plane between two loops stops once its margin is within this factor of the
/// widest possible (see separatingPlane); it need not be the widest, only to separate.
constexpr double kNearWidest = 0.9;

/// The search's steps at most. Loops a cell apart converge in a handful; loops whose hulls meet
/// (no plane separates them) shrink the step towards 0, and are left as they are.
constexpr int kPlaneSteps = 64;

/// A loop's crossings and their mass point.
struct Loop {
    std::array<Vec3, kCellEdges> p;
    int len = 0;
    Vec3 mass{0.0};
};

Loop loopOf(const SharedPatch& patch, const Vec3* points) {
    Loop out;
    out.len = patch.len;
    for (int i = 0; i < patch.len; ++i) {
        out.p[std::size_t(i)] = points[patch.loop[i]];
        out.mass += out.p[std::size_t(i)];
    }
    out.mass /= double(patch.len);
    return out;
}

/// A patch's fan: vertex, loop[i], loop[i + 1].
std::array<Mesh::Triangle, kCellEdges> fanOf(const SharedPatch& s) {
    std::array<Mesh::Triangle, kCellEdges> fan{};
    for (int i = 0; i < s.len; ++i)
        fan[std::size_t(i)] = {s.vertex, s.loop[i], s.loop[i + 1 == s.len ? 0 : i + 1]};
    return fan;
}

/// Whether a triangle of patch k's fan passes through one of patch l's by more than tol.
bool fansCross(const SharedPatch& k, const SharedPatch& l, const Vec3* points, double tol) {
    const std::array<Mesh::Triangle, kCellEdges> a = fanOf(k), b = fanOf(l);
    return !fanCrossings(a.data(), k.len, b.data(), l.len, points, tol).empty();
}

/// A plane between the crossings of loops a and b: its unit normal n, pointing towards a, and
/// offset c, with n . p - c >= margin for a's crossings and <= -margin for b's; false when the
/// search finds none with margin > 0 (the loops' hulls meet).
///
/// The widest such plane lies across the shortest vector between the two hulls, the point of the
/// hull of the differences a_i - b_j nearest the origin, which Gilbert's algorithm (1966) finds:
/// from a point x of that hull, the difference s of the crossings farthest along -x and along x
/// bounds the distance d between the hulls as x . s / |x| <= d <= |x|; x steps to the point of the
/// segment x-s nearest the origin, until x . s reaches kNearWidest |x|^2. The plane across x
/// midway between the two loops then has a margin (lo - hi) / 2 = x . s / (2 |x|) of at least
/// kNearWidest d / 2: kNearWidest of the widest plane's, d / 2.
bool separatingPlane(const Loop& a, const Loop& b, Vec3& n, double& c, double& margin) {
    Vec3 x = a.mass - b.mass;
    for (int step = 0; step < kPlaneSteps; ++step) {
        const double xx = glm::dot(x, x);
        if (!(xx > 0.0)) return false;
        Vec3 sa = a.p[0], sb = b.p[0];
        for (int i = 1; i < a.len; ++i)
            if (glm::dot(x, a.p[std::size_t(i)]) < glm::dot(x, sa)) sa = a.p[std::size_t(i)];
        for (int i = 1; i < b.len; ++i)
            if (glm::dot(x, b.p[std::size_t(i)]) > glm::dot(x, sb)) sb = b.p[std::size_t(i)];
        const Vec3 s = sa - sb;
        if (glm::dot(x, s) >= kNearWidest * xx) break;
        const Vec3 d = s - x;
        const double dd = glm::dot(d, d);
        if (!(dd > 0.0)) break;
        x += glm::clamp(-glm::dot(x, d) / dd, 0.0, 1.0) * d;
    }
    const double length = glm::length(x);
    if (!(length > 0.0)) return false;
    n = x / length;
    double lo = glm::dot(n, a.p[0]), hi = glm::dot(n, b.p[0]);
    for (int i = 1; i < a.len; ++i) lo = std::min(lo, glm::dot(n, a.p[std::size_t(i)]));
    for (int i = 1; i < b.len; ++i) hi = std::max(hi, glm::dot(n, b.p[std::size_t(i)]));
    c = 0.5 * (lo + hi);
    margin = 0.5 * (lo - hi);
    return margin > 0.0;
}

/// Moves v towards `mass` until n . v - c >= want, where n . mass - c >= want already; true if it
/// moved.
bool moveToSide(Vec3& v, const Vec3& mass, const Vec3& n, double c, double want) {
    const double at = glm::dot(n, v) - c;
    if (at >= want) return false;
    const double to = glm::dot(n, mass) - c;
    v += ((want - at) / (to - at)) * (mass - v);
    return true;
}

}  // namespace

/// Each patch's vertex is placed from its own loop alone (PatchVertexRule::place), within the box
/// of its crossings where it shares its cell, and two vertices can still pass each other there. A
/// fin thinner than the cell that crosses an ambiguous face slantwise is cut by the asymptotic
/// decider where the level set's corner values, distances to the nearer side, make the face's
/// saddle air: each of the cell's patches then holds crossings of both sides of the fin, whose
/// tangent planes meet past the walls, which curve towards each other. Between two ball plunges of
/// radius 5 h whose walls pass 0.0095 h apart at (9.21, 9.42, 1.08), in the cell at (7.5, 7.5,
/// 1.5), the patch round three corners was fitted at (8.366, 8.499, 1.574), 0.028 h past the
/// chord, on the face y = 8.5, of the patch that cuts off the fourth corner (8.5, 8.5, 1.5); five
/// pairs of their fan triangles passed through each other, none folded. At radius 5 h 13 of 3000
/// such pairs of plunges did so (73 pairs of triangles).
///
/// The loops of a cell's patches lie apart on its faces, and where their hulls are apart a plane
/// separates them (separatingPlane). A fan whose vertex lies on its loop's side of the plane lies
/// there whole (each triangle is the hull of its vertex and two crossings), so two such fans
/// cannot meet. Of a pair whose fans cross, each vertex short of kOwnSide of its loop's distance
/// from the plane is moved towards its loop's mass point, which lies at least that distance on its
/// side, until it stands that far: as fold repair pulls a vertex, and no farther. The move stays in
/// the box the vertex was kept in (the mass point lies in it), and a later pull towards the mass
/// point, by fold repair, keeps it on its side. A cell holds at most four patches of a few
/// triangles each, so every pair is tested; a pair once set apart stays apart as others move, so
/// the sweeps end after at most one per pair.
///
/// Where the two loops' hulls meet, no plane lies between them and the pair is left crossing; the
/// count of such pairs goes into ContourStats::patchPairsLeftCrossing.
PatchesApart keepPatchesApart(const SharedPatch* patches, int count, Vec3* points, double tol) {
    std::array<std::array<bool, kMaxPatches>, kMaxPatches> apart{};
    PatchesApart out;
    for (bool again = true; again;) {
        again = false;
        for (int k = 0; k < count; ++k)
            for (int l = k + 1; l < count; ++l) {
                if (apart[std::size_t(k)][std::size_t(l)] || !fansCross(patches[k], patches[l], points, tol)) continue;
                apart[std::size_t(k)][std::size_t(l)] = true;
                const Loop a = loopOf(patches[k], points), b = loopOf(patches[l], points);
                Vec3 n(0.0);
                double c = 0.0, margin = 0.0;
                if (!separatingPlane(a, b, n, c, margin)) {
                    ++out.leftCrossing;
                    continue;
                }
                again = true;
                out.moved += moveToSide(points[patches[k].vertex], a.mass, n, c, kOwnSide * margin);
                out.moved +=
                    moveToSide(points[patches[l].vertex], b.mass, -n, -c, kOwnSide * margin);
            }
    }
    return out;
}

}  // namespace dexelmill::detail
