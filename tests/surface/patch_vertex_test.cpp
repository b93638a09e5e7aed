// The dexel mesher's patch vertex (surface/detail/patch_vertex.h) against answers found another
// way: a concave corner and a concave crease solved by Cramer's rule on the crossings' planes, a
// smooth patch's offset along its mean normal by a ternary search of the squared distances, a
// convex ridge held within its crossings' box, and loops without planes. The planes are the packed
// normals' (as the mesher sees them), so each answer is exact; the true corner or crease lies
// within the packing's error of it. A crease's or corner's vertex is kept a thousandth of a
// spacing inside its cell's faces. Random cases on fixed seeds.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <random>
#include <vector>

#include "surface/detail/patch_vertex.h"

using namespace dexelmill;
using detail::PatchVertexRule;

namespace {

constexpr double kFeatureAngle = 0.6;  // ContourOptions' default

struct Patch {
    std::vector<Vec3> points;
    std::vector<PackedNormal> normals;
    std::vector<std::uint32_t> index;

    void add(const Vec3& p, const PackedNormal& n) {
        index.push_back(std::uint32_t(points.size()));
        points.push_back(p);
        normals.push_back(n);
    }
    PatchVertexRule::Loop loop() const { return {points.data(), normals.data(), index.data(), int(index.size())}; }
    Vec3 mass() const {
        Vec3 m(0.0);
        for (const Vec3& p : points) m += p;
        return m / double(points.size());
    }
    Vec3 boxLo() const {
        Vec3 lo = points[0];
        for (const Vec3& p : points) lo = Vec3(std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z));
        return lo;
    }
    Vec3 boxHi() const {
        Vec3 hi = points[0];
        for (const Vec3& p : points) hi = Vec3(std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z));
        return hi;
    }
};

/// The rule's margin: a crease's or corner's vertex stays a thousandth of a spacing inside its
/// cell's faces.
Vec3 insideCell(const Vec3& p, const Vec3& cellLo, double h) {
    return glm::clamp(p, cellLo + 1e-3 * h, cellLo + Vec3(h - 1e-3 * h));
}

double det3(const Vec3& a, const Vec3& b, const Vec3& c) {
    return a.x * (b.y * c.z - b.z * c.y) - a.y * (b.x * c.z - b.z * c.x) + a.z * (b.x * c.y - b.y * c.x);
}

/// Solves M x = r by Cramer's rule, M given by its columns.
Vec3 cramer3(const Vec3& c0, const Vec3& c1, const Vec3& c2, const Vec3& r) {
    const double d = det3(c0, c1, c2);
    return Vec3(det3(r, c1, c2) / d, det3(c0, r, c2) / d, det3(c0, c1, r) / d);
}

/// A rotation from three uniform numbers (Shoemake's uniform unit quaternion), as its columns.
void randomFrame(std::mt19937& rng, Vec3& ex, Vec3& ey, Vec3& ez) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double u1 = u(rng), u2 = 2.0 * M_PI * u(rng), u3 = 2.0 * M_PI * u(rng);
    const double a = std::sqrt(1.0 - u1) * std::sin(u2), b = std::sqrt(1.0 - u1) * std::cos(u2);
    const double c = std::sqrt(u1) * std::sin(u3), w = std::sqrt(u1) * std::cos(u3);
    ex = Vec3(1 - 2 * (b * b + c * c), 2 * (a * b + c * w), 2 * (a * c - b * w));
    ey = Vec3(2 * (a * b - c * w), 1 - 2 * (a * a + c * c), 2 * (b * c + a * w));
    ez = Vec3(2 * (a * c + b * w), 2 * (b * c - a * w), 1 - 2 * (a * a + b * b));
}

/// The point on the two planes u1 . x = d1 and u2 . x = d2 nearest m (unit u1, u2).
Vec3 nearestOnLine(const Vec3& m, const Vec3& u1, double d1, const Vec3& u2, double d2) {
    const double c = glm::dot(u1, u2);
    const double r1 = d1 - glm::dot(u1, m), r2 = d2 - glm::dot(u2, m);
    const double det = 1.0 - c * c;
    const double alpha = (r1 - c * r2) / det, beta = (r2 - c * r1) / det;
    return m + alpha * u1 + beta * u2;
}

/// The mean of u . p over some points.
double meanOffset(const Vec3& u, const std::vector<Vec3>& points) {
    double s = 0.0;
    for (const Vec3& p : points) s += glm::dot(u, p);
    return s / double(points.size());
}

}  // namespace

TEST_CASE("patch vertex: a concave corner is where its three planes meet, within the cell",
          "[surface][contour]") {
    std::mt19937 rng(20261127);
    std::uniform_real_distribution<double> along(0.05, 0.4), where(-0.3, 1.3), origin(-50.0, 50.0);
    const double h = 0.3;
    const PatchVertexRule rule(h, kFeatureAngle);
    for (int trial = 0; trial < 300; ++trial) {
        Vec3 axis[3];
        randomFrame(rng, axis[0], axis[1], axis[2]);
        const Vec3 cellLo(origin(rng), origin(rng), origin(rng));
        const Vec3 corner = cellLo + h * Vec3(where(rng), where(rng), where(rng));
        // The air is the octant where every axis[i] . (x - corner) > 0; face i of it has
        // outward (into the air) normal axis[i]; two crossings on each face.
        Patch patch;
        for (int i = 0; i < 3; ++i) {
            const PackedNormal n = PackedNormal::pack(axis[i]);
            for (int k = 0; k < 2; ++k)
                patch.add(corner + h * (along(rng) * axis[(i + 1) % 3] + along(rng) * axis[(i + 2) % 3]), n);
        }
        int rank = -1;
        const Vec3 v = rule.place(patch.loop(), cellLo, false, rank);
        // The packed planes' least-squares point: sum_i u_i u_i^T x = sum_i u_i (u_i . p_i).
        Vec3 col[3] = {Vec3(0.0), Vec3(0.0), Vec3(0.0)};
        Vec3 rhs(0.0);
        for (std::size_t j = 0; j < patch.points.size(); ++j) {
            const Vec3 u = patch.normals[j].unpack();
            for (int c = 0; c < 3; ++c) col[c] += u * u[c];
            rhs += u * glm::dot(u, patch.points[j]);
        }
        const Vec3 meet = cramer3(col[0], col[1], col[2], rhs);
        const Vec3 want = insideCell(meet, cellLo, h);
        INFO("trial " << trial);
        CHECK(rank == 3);
        CHECK(glm::length(v - want) <= 1e-9 * h);
        // The true corner is within the packing's error (1.3e-4 rad over at most 0.6 h) of it.
        CHECK(glm::length(meet - corner) <= 1e-3 * h);
    }
}

namespace {

/// Two faces whose normals n1, n2 lie beta (random in [0.8, 2.3]) apart about the line through
/// `apex` along d, in a random frame. Concave: the air lies on the outer side of both (a V-groove's
/// bottom when beta is small, an obtuse floor-wall corner when it is large). Convex: the material is
/// the wedge where n1 . (x - apex) <= 0 and n2 . (x - apex) <= 0 (a ridge). Crossing k lies on face
/// faces[k], `reach` h from the line across its face and up to 0.3 h along it. `line` is the point
/// of the packed planes' line nearest the crossings' mean, by a 2x2 solve.
struct Wedge {
    Patch patch;
    Vec3 line;
    double beta;
};

Wedge makeWedge(std::mt19937& rng, bool concave, std::uniform_real_distribution<double>& reach,
                std::uniform_real_distribution<double>& where, std::initializer_list<int> faces, double h) {
    std::uniform_real_distribution<double> side(-0.3, 0.3), turn(0.8, 2.3);
    Vec3 ex, ey, d;
    randomFrame(rng, ex, ey, d);
    Wedge w;
    w.beta = turn(rng);
    const Vec3 n[2] = {ex, std::cos(w.beta) * ex + std::sin(w.beta) * ey};
    // Along each face, away from the line: into the other face's air side (concave) or material
    // side (convex).
    Vec3 t[2] = {glm::cross(d, n[0]), glm::cross(d, n[1])};
    for (int f = 0; f < 2; ++f)
        if ((glm::dot(n[1 - f], t[f]) < 0.0) == concave) t[f] = -t[f];
    const Vec3 apex = h * Vec3(where(rng), where(rng), where(rng));
    std::vector<Vec3> on[2];
    for (int f : faces) {
        on[f].push_back(apex + h * (reach(rng) * t[f] + side(rng) * d));
        w.patch.add(on[f].back(), PackedNormal::pack(n[f]));
    }
    const Vec3 u1 = PackedNormal::pack(n[0]).unpack(), u2 = PackedNormal::pack(n[1]).unpack();
    w.line = nearestOnLine(w.patch.mass(), u1, meanOffset(u1, on[0]), u2, meanOffset(u2, on[1]));
    return w;
}

}  // namespace

TEST_CASE("patch vertex: a concave crease puts the vertex on it, nearest the crossings' mean",
          "[surface][contour]") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> inward(0.05, 0.4), where(0.2, 0.8);
    const double h = 1.0;
    const PatchVertexRule rule(h, kFeatureAngle);
    for (int trial = 0; trial < 300; ++trial) {
        const Wedge w = makeWedge(rng, true, inward, where, {0, 0, 0, 1, 1}, h);
        int rank = -1;
        const Vec3 v = rule.place(w.patch.loop(), Vec3(0.0), false, rank);
        const Vec3 want = insideCell(w.line, Vec3(0.0), h);
        INFO("trial " << trial << " beta " << w.beta);
        CHECK(rank == 2);
        CHECK(glm::length(v - want) <= 1e-9 * h);
    }
}

TEST_CASE("patch vertex: a convex ridge stays within its crossings' box", "[surface][contour]") {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> down(0.1, 0.4), where(0.3, 0.7);
    const double h = 1.0;
    const PatchVertexRule rule(h, kFeatureAngle);
    int clamped = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const Wedge w = makeWedge(rng, false, down, where, {0, 1, 0, 1}, h);
        int rank = -1;
        const Vec3 v = rule.place(w.patch.loop(), Vec3(0.0), false, rank);
        const Vec3 want = insideCell(glm::clamp(w.line, w.patch.boxLo(), w.patch.boxHi()), Vec3(0.0), h);
        clamped += glm::length(want - w.line) > 1e-6 * h;
        INFO("trial " << trial << " beta " << w.beta);
        CHECK(rank == 2);
        CHECK(glm::length(v - want) <= 1e-9 * h);
    }
    // The box binds in some cases (the ridge lies beyond the crossings), or the test shows nothing.
    CHECK(clamped > 30);
}

TEST_CASE("patch vertex: a patch that shares its cell stays within its crossings' box", "[surface][contour]") {
    // One end of a fin 0.05 h thick, slanting across the cell's z faces: its two sides cross the
    // y edges at x = 1 (normals +-n, no z part), and the face rule's face vertices lie far across
    // the faces at x = 0.001 (no normal). The least-squares point lies on the fin's middle plane
    // n . x = n . (1, 0.15665, 0), straight along n from the crossings' mean (0.667, 0.148, 0.5):
    // 0.19 along n = (0.591, -0.806, 0) / |.|, at y = -0.005, below the cell. Bounded by the cell
    // alone it sits on the face y = 0, where the fin's other end has its patch in the same cell.
    const double h = 1.0;
    const PatchVertexRule rule(h, kFeatureAngle);
    const Vec3 n = glm::normalize(Vec3(0.591, -0.806, 0.0));
    Patch stub;
    stub.add(Vec3(1.0, 0.1308, 0.0), PackedNormal::pack(n));
    stub.add(Vec3(1.0, 0.1308, 1.0), PackedNormal::pack(n));
    stub.add(Vec3(0.001, 0.1308, 1.0), PackedNormal());
    stub.add(Vec3(1.0, 0.1825, 1.0), PackedNormal::pack(-n));
    stub.add(Vec3(1.0, 0.1825, 0.0), PackedNormal::pack(-n));
    stub.add(Vec3(0.001, 0.1308, 0.0), PackedNormal());
    int rank = -1;
    const Vec3 alone = rule.place(stub.loop(), Vec3(0.0), false, rank);
    CHECK(alone.y < 0.1308);  // the case this guards: the cell's bound leaves the fin
    const Vec3 shared = rule.place(stub.loop(), Vec3(0.0), true, rank);
    CHECK(rank == 1);
    CHECK(shared == glm::clamp(shared, stub.boxLo(), stub.boxHi()));
    CHECK(shared.y == Approx(0.1308));  // the fit point's y clamped to the box's
}

TEST_CASE("patch vertex: a ridge beyond a cell face leaves the vertex a thousandth of a spacing inside it",
          "[surface][contour]") {
    // The roof z <= 0.5 h, x + z >= 0.3 h has its ridge at x = -0.2 h, outside the cell: the
    // crossings' box puts the vertex on the face x = 0, where its fan over a lens on that face
    // would lie in the face (on heart, three such fan triangles overlapped). It stays 1e-3 h in.
    const double h = 0.25;
    const Vec3 cellLo(3.0, -2.0, 1.0);
    const PatchVertexRule rule(h, kFeatureAngle);
    Patch roof;
    const PackedNormal top = PackedNormal::pack(Vec3(0.0, 0.0, 1.0));
    const PackedNormal slope = PackedNormal::pack(glm::normalize(Vec3(-1.0, 0.0, -1.0)));
    roof.add(cellLo + h * Vec3(0.3, 0.2, 0.5), top);
    roof.add(cellLo + h * Vec3(0.8, 0.7, 0.5), top);
    roof.add(cellLo + h * Vec3(0.2, 0.8, 0.1), slope);
    roof.add(cellLo + h * Vec3(0.0, 0.3, 0.3), slope);
    int rank = -1;
    const Vec3 v = rule.place(roof.loop(), cellLo, false, rank);
    CHECK(rank == 2);
    // The ridge line runs along y, so the vertex takes the crossings' mean y.
    const Vec3 want = cellLo + h * Vec3(1e-3, 0.5, 0.5);
    CHECK(glm::length(v - want) <= 2e-4 * h);  // the packed normals' error (1.3e-4 rad) over 0.5 h
    CHECK(v.x - cellLo.x >= 1e-3 * h * (1.0 - 1e-9));
}

TEST_CASE("patch vertex: a smooth patch moves along its mean normal to the planes' least squares",
          "[surface][contour]") {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> spread(-0.1, 0.1), radius(3.0, 30.0);
    const double h = 1.0;
    const PatchVertexRule rule(h, kFeatureAngle);
    for (int trial = 0; trial < 300; ++trial) {
        Vec3 ex, ey, up;
        randomFrame(rng, ex, ey, up);
        // Crossings on a sphere (the inside of a ball end's cut: the material outside it), in
        // directions within 0.15 rad of `up`, in order around it; their normals point to the centre.
        const double r = radius(rng) * h;
        const Vec3 centre = Vec3(0.5 * h) + r * up;
        Patch patch;
        const int n = 4 + trial % 3;
        for (int k = 0; k < n; ++k) {
            const double a = 2.0 * M_PI * k / n;
            const double tilt = 0.25 * h / r + 0.3 * spread(rng) * h / r;
            const Vec3 dir = glm::normalize(-up + tilt * (std::cos(a) * ex + std::sin(a) * ey));
            patch.add(centre + r * dir, PackedNormal::pack(-dir));
        }
        int rank = -1;
        const Vec3 v = rule.place(patch.loop(), Vec3(0.0), false, rank);
        // The mean normal, and the offset along it minimising the sum of squared plane distances,
        // by a ternary search (the sum is a convex quadratic in the offset).
        const Vec3 m = patch.mass();
        Vec3 mean(0.0);
        for (const PackedNormal& pn : patch.normals) mean += pn.unpack();
        mean = glm::normalize(mean);
        auto cost = [&](double s) {
            double sum = 0.0;
            for (std::size_t j = 0; j < patch.points.size(); ++j) {
                const double e = glm::dot(patch.normals[j].unpack(), m + s * mean - patch.points[j]);
                sum += e * e;
            }
            return sum;
        };
        double lo = -h, hi = h;
        for (int it = 0; it < 200; ++it) {
            const double a = lo + (hi - lo) / 3.0, b = hi - (hi - lo) / 3.0;
            (cost(a) < cost(b) ? hi : lo) = cost(a) < cost(b) ? b : a;
        }
        const Vec3 want = glm::clamp(m + 0.5 * (lo + hi) * mean, Vec3(0.0), Vec3(h));
        INFO("trial " << trial);
        CHECK(rank == 1);
        CHECK(glm::length(v - want) <= 1e-9 * h);
    }
}

TEST_CASE("patch vertex: without a plane the vertex is the crossings' mean", "[surface][contour]") {
    const PatchVertexRule rule(1.0, kFeatureAngle);
    Patch none, sharp;
    const Vec3 pts[4] = {{0.2, 0.0, 0.5}, {1.0, 0.3, 0.5}, {0.6, 1.0, 0.5}, {0.0, 0.7, 0.5}};
    for (const Vec3& p : pts) {
        none.add(p, PackedNormal{});
        sharp.add(p, PackedNormal::pack(Vec3(0.0, 0.0, 1.0), true));  // marked sharp: no plane
    }
    for (const Patch* patch : {&none, &sharp}) {
        int rank = -1;
        const Vec3 v = rule.place(patch->loop(), Vec3(0.0), false, rank);
        CHECK(rank == 0);
        CHECK(glm::length(v - Vec3(0.45, 0.5, 0.5)) <= 1e-12);
    }
}
