// Round stocks (cylinder, cone frustum): the closed-form chord of a line against a brute-force
// oracle that knows only the solid's definition, and the stock cast from it.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "dexelmill/error.h"
#include "dexelmill/stock/primitive.h"

using namespace dexelmill;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// The oracle's solid: F(p) = max(-t, t - H, radial - r(t)) is negative exactly inside, zero on the
/// surface, and convex (each piece is), so along a line it is a convex function of s. The radial
/// distance comes from a cross product here, not from the solver's projection.
struct OracleFrustum {
    Vec3 base, d;
    double H, r0, r1;
    double t(const Vec3& p) const { return glm::dot(p - base, d); }
    double radial(const Vec3& p) const { return glm::length(glm::cross(p - base, d)); }
    double sidePiece(const Vec3& p) const { return radial(p) - (r0 + (r1 - r0) * t(p) / H); }
    double F(const Vec3& p) const { return std::max({-t(p), t(p) - H, sidePiece(p)}); }
};

/// The chord by search: the minimum of the convex F along the line by golden sections, then each
/// root of F = 0 on either side by bisection. `depth` is -min F (how far inside the line gets).
struct OracleChord {
    bool empty = true;
    double lo = 0, hi = 0, depth = 0;
};

OracleChord oracleChord(const OracleFrustum& f, const Vec3& o, const Vec3& e, double span) {
    auto F = [&](double s) { return f.F(o + s * e); };
    double a = -span, b = span;
    const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
    for (int i = 0; i < 200; ++i) {
        const double c = b - phi * (b - a), d = a + phi * (b - a);
        (F(c) < F(d) ? b : a) = (F(c) < F(d) ? d : c);
    }
    const double sMin = 0.5 * (a + b);
    OracleChord out;
    out.depth = -F(sMin);
    if (!(F(sMin) < 0.0)) return out;
    auto root = [&](double inside, double outside) {
        for (int i = 0; i < 200; ++i) {
            const double mid = 0.5 * (inside + outside);
            (F(mid) < 0.0 ? inside : outside) = mid;
        }
        return 0.5 * (inside + outside);
    };
    out.empty = false;
    out.lo = root(sMin, -span);
    out.hi = root(sMin, span);
    return out;
}

/// The oracle's outward normal at a surface point: the normalised central-difference gradient of
/// the one piece of F that is zero there; none (zero) on a rim, where two pieces are.
Vec3 oracleNormal(const OracleFrustum& f, const Vec3& p, double scale) {
    const double rim = 1e-7 * scale;
    const double pieces[3] = {-f.t(p), f.t(p) - f.H, f.sidePiece(p)};
    int active = -1, near = 0;
    for (int i = 0; i < 3; ++i) {
        if (std::abs(pieces[i]) <= rim) {
            active = i;
            ++near;
        }
    }
    if (near != 1) return Vec3(0.0);
    if (active == 0) return -f.d;
    if (active == 1) return f.d;
    const double step = 1e-6 * scale;
    Vec3 g;
    for (int i = 0; i < 3; ++i) {
        Vec3 dp(0.0);
        dp[i] = step;
        g[i] = (f.sidePiece(p + dp) - f.sidePiece(p - dp)) / (2 * step);
    }
    return glm::normalize(g);
}

Vec3 randomUnit(std::mt19937& rng) {
    std::normal_distribution<double> n(0.0, 1.0);
    Vec3 v(n(rng), n(rng), n(rng));
    return glm::normalize(v);
}

/// Compares the solver's chord with the oracle's for one line.
void checkLine(const Frustum& f, const OracleFrustum& of, const Vec3& o, const Vec3& e) {
    const double scale = std::max({f.height, f.r0, f.r1});
    const double span = 4.0 * scale + glm::length(o - f.base);
    const FrustumChord c = frustumChord(f, o, e);
    const OracleChord oc = oracleChord(of, o, e, span);
    // A line that only grazes the solid (less than 1e-6 of its size deep) may come out either way;
    // its chord must then be short and on the surface.
    const double grazing = 1e-6 * scale;
    INFO("base " << f.base.x << "," << f.base.y << "," << f.base.z << " axis " << f.axis.x << "," << f.axis.y << ","
                 << f.axis.z << " H " << f.height << " r " << f.r0 << "," << f.r1 << " line " << o.x << "," << o.y
                 << "," << o.z << " dir " << e.x << "," << e.y << "," << e.z << " depth " << oc.depth);
    if (oc.depth < grazing) {
        if (!c.empty) {
            CHECK(std::abs(of.F(o + c.lo * e)) <= 1e-6 * scale);
            CHECK(std::abs(of.F(o + c.hi * e)) <= 1e-6 * scale);
        }
        return;
    }
    REQUIRE_FALSE(c.empty);
    // Ends to 1e-9 of the size, scaled by how steeply F rises there (a line nearly tangent to the
    // side meets it at a shallow angle, where the root is as ill-conditioned as that angle).
    const double slopeLo = (of.F(o + (oc.lo - 1e-4 * scale) * e) - of.F(o + oc.lo * e)) / (1e-4 * scale);
    const double slopeHi = (of.F(o + (oc.hi + 1e-4 * scale) * e) - of.F(o + oc.hi * e)) / (1e-4 * scale);
    CHECK(std::abs(c.lo - oc.lo) <= 1e-9 * scale / std::min(1.0, std::max(slopeLo, 1e-3)));
    CHECK(std::abs(c.hi - oc.hi) <= 1e-9 * scale / std::min(1.0, std::max(slopeHi, 1e-3)));
    // Normals, where the oracle sees a single piece of surface.
    const Vec3 nlo = oracleNormal(of, o + c.lo * e, scale), nhi = oracleNormal(of, o + c.hi * e, scale);
    if (nlo != Vec3(0.0)) {
        CHECK(glm::length(c.nlo - nlo) <= 1e-5);
        CHECK_FALSE(c.sharpLo);
    }
    if (nhi != Vec3(0.0)) {
        CHECK(glm::length(c.nhi - nhi) <= 1e-5);
        CHECK_FALSE(c.sharpHi);
    }
    // Outward: against the line's direction where it enters, along it where it leaves.
    CHECK(glm::dot(c.nlo, e) <= 1e-12);
    CHECK(glm::dot(c.nhi, e) >= -1e-12);
}

}  // namespace

TEST_CASE("a frustum's chord agrees with a brute-force oracle on random lines", "[stock][primitive]") {
    std::mt19937 rng(20261123);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    const Vec3 lattice[3] = {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
    for (int shape = 0; shape < 60; ++shape) {
        const Vec3 base(40 * U(rng) - 20, 40 * U(rng) - 20, 40 * U(rng) - 20);
        // Lattice axes, reversed lattice axes and arbitrary ones.
        const Vec3 axis = shape % 3 == 0 ? lattice[shape % 9 / 3] : shape % 3 == 1 ? -lattice[shape % 9 / 3]
                                                                                 : randomUnit(rng);
        const double H = 1 + 30 * U(rng);
        // Cylinders, cones to an apex at either end, and general frustums.
        double r0 = 1 + 20 * U(rng), r1 = 1 + 20 * U(rng);
        if (shape % 4 == 1) r1 = r0;
        if (shape % 8 == 2) r1 = 0;
        if (shape % 8 == 6) r0 = 0;
        const Frustum f = Frustum::make(base, 2.5 * axis, H, r0, r1);
        const OracleFrustum of{base, axis, H, r0, r1};
        const double reach = std::max({H, r0, r1});
        for (int l = 0; l < 60; ++l) {
            const Vec3 through = base + axis * (H * (1.4 * U(rng) - 0.2)) +
                                 randomUnit(rng) * (1.2 * std::max(r0, r1) * U(rng));
            // Dexel directions and arbitrary ones; the origin somewhere along the line.
            const Vec3 e = l % 2 == 0 ? lattice[l % 6 / 2] : randomUnit(rng);
            checkLine(f, of, through - e * (reach * (4 * U(rng) - 2)), e);
        }
    }
}

TEST_CASE("a frustum's chord in the degenerate cases", "[stock][primitive]") {
    const Vec3 z(0, 0, 1), x(1, 0, 0);
    const Frustum cyl = Frustum::make(Vec3(0.0), z, 10, 4, 4);
    const Frustum cone = Frustum::make(Vec3(0.0), z, 10, 5, 0);

    SECTION("along a cylinder's axis: the faces, with their normals") {
        const FrustumChord c = frustumChord(cyl, Vec3(1, 1, -3), z);
        REQUIRE_FALSE(c.empty);
        CHECK(c.lo == Approx(3).margin(1e-12));
        CHECK(c.hi == Approx(13).margin(1e-12));
        CHECK(c.nlo == -z);
        CHECK(c.nhi == z);
        CHECK_FALSE(c.sharpLo);
        CHECK_FALSE(c.sharpHi);
    }
    SECTION("outside a cylinder, parallel to its axis, and on its side") {
        CHECK(frustumChord(cyl, Vec3(5, 0, 0), z).empty);
        CHECK(frustumChord(cyl, Vec3(4, 0, 0), z).empty);
    }
    SECTION("tangent to the side, and in the plane of a face") {
        CHECK(frustumChord(cyl, Vec3(0, 4, 5), x).empty);
        CHECK(frustumChord(cyl, Vec3(0, 0, 10), x).empty);
        CHECK(frustumChord(cyl, Vec3(0, 0, 0), x).empty);
    }
    SECTION("across the axis: 2 sqrt(r^2 - d^2)") {
        const FrustumChord c = frustumChord(cyl, Vec3(-10, 2, 5), x);
        REQUIRE_FALSE(c.empty);
        CHECK(c.hi - c.lo == Approx(2 * std::sqrt(12.0)).epsilon(1e-14));
        CHECK(c.nlo.x == Approx(-std::sqrt(12.0) / 4));
        CHECK(c.nlo.y == Approx(0.5));
    }
    SECTION("along a cone's axis to its apex: a sharp end there") {
        const FrustumChord c = frustumChord(cone, Vec3(0, 0, -1), z);
        REQUIRE_FALSE(c.empty);
        CHECK(c.lo == Approx(1).margin(1e-12));
        CHECK(c.hi == Approx(11).margin(1e-12));
        CHECK(c.nhi == z);
        CHECK(c.sharpHi);
        CHECK_FALSE(c.sharpLo);
    }
    SECTION("along a generator of the cone: on its surface, then inside it in parallel") {
        // The generator from (5, 0, 0) to the apex (0, 0, 10); A = 0 in the quadratic.
        const Vec3 g = glm::normalize(Vec3(-5, 0, 10));
        CHECK(frustumChord(cone, Vec3(5, 0, 0), g).empty);
        // Shifted 1 mm inwards along x, it enters through the base at x = 4.
        const FrustumChord c = frustumChord(cone, Vec3(4, 0, 0), g);
        REQUIRE_FALSE(c.empty);
        CHECK(c.lo == Approx(0).margin(1e-12));
        CHECK(c.nlo == -z);
        // It reaches the side where its distance to the axis, |4 - t / 2|, equals 5 - t / 2 on
        // the far side of the axis: t / 2 - 4 = 5 - t / 2, t = 9.
        CHECK(c.hi * g.z == Approx(9).epsilon(1e-12));
        const Vec3 n = glm::normalize(Vec3(-1, 0, 0.5));
        CHECK(glm::length(c.nhi - n) < 1e-12);
    }
    SECTION("through a rim: a sharp end") {
        // Along the base plane's diagonal direction into the base rim at (4, 0, 0) from below.
        const Vec3 d = glm::normalize(Vec3(1, 0, 1));
        const FrustumChord c = frustumChord(cyl, Vec3(4, 0, 0) - 2.0 * d, d);
        CHECK(c.empty);  // it leaves the solid at once: only the rim is touched
        const FrustumChord in = frustumChord(cyl, Vec3(-4, 0, 0) - 2.0 * d, d);
        REQUIRE_FALSE(in.empty);
        CHECK(in.sharpLo);
        CHECK(in.lo == Approx(2).margin(1e-12));
    }
}

TEST_CASE("a frustum's bounds and volume", "[stock][primitive]") {
    const Frustum f = Frustum::make(Vec3(1, 2, 3), Vec3(0, 0, -2), 10, 3, 1);
    const Box b = f.bounds();
    CHECK(b.lo.x == Approx(-2));
    CHECK(b.hi.y == Approx(5));
    CHECK(b.lo.z == Approx(-7));
    CHECK(b.hi.z == Approx(3));
    CHECK(f.volume() == Approx(kPi * 10 * 13 / 3.0));
    // A tilted cylinder: the disc's reach is r sqrt(1 - a_i^2).
    const Frustum t = Frustum::make(Vec3(0.0), Vec3(1, 0, 1), std::sqrt(2.0) * 10, 2, 2);
    CHECK(t.bounds().lo.x == Approx(-std::sqrt(2.0)));
    CHECK(t.bounds().hi.x == Approx(10 + std::sqrt(2.0)));
    CHECK(t.bounds().hi.y == Approx(2));
}

TEST_CASE("impossible frustums are refused", "[stock][primitive]") {
    CHECK_THROWS_AS(Frustum::make(Vec3(0.0), Vec3(0.0), 1, 1, 1), Error);
    CHECK_THROWS_AS(Frustum::make(Vec3(0.0), Vec3(0, 0, 1), 0, 1, 1), Error);
    CHECK_THROWS_AS(Frustum::make(Vec3(0.0), Vec3(0, 0, 1), 1, -1, 1), Error);
    CHECK_THROWS_AS(Frustum::make(Vec3(0.0), Vec3(0, 0, 1), 1, 0, 0), Error);
    CHECK_THROWS_AS(Frustum::make(Vec3(0.0), Vec3(0, 0, 1), 1, std::nan(""), 1), Error);
}

TEST_CASE("a round stock holds the frustum's chord on every dexel", "[stock][primitive]") {
    const Frustum f = Frustum::make(Vec3(-3, 1, 2), Vec3(1, 0.3, 0.2), 20, 6, 2);
    const OracleFrustum of{f.base, f.axis, f.height, f.r0, f.r1};
    const double h = 0.4;
    const TriDexelStock s = stockFromFrustum(f, Lattice::fromBox(f.bounds(), h));
    const Lattice& l = s.lattice();
    CHECK(l.origin == f.bounds().lo);
    for (int a = 0; a < 3; ++a) {
        const Axis axis = axisFromIndex(a);
        const DexelFamily& fam = s.family(axis);
        int crossing = 0;
        for (int ic = 0; ic < fam.nc(); ++ic) {
            for (int ib = 0; ib < fam.nb(); ++ib) {
                const Line line = s.dexelLine(axis, ib, ic);
                const OracleChord oc = oracleChord(of, line.origin, line.dir, 100.0);
                const SegmentSpan segs = fam.segments(ib, ic);
                if (oc.depth < -1e-6) CHECK(segs.empty());
                if (oc.depth < 1e-6) continue;
                REQUIRE(segs.size == 1);
                ++crossing;
                // Floats of a few tens of mm: 4e-6 mm.
                CHECK(segs[0].lo == Approx(oc.lo).margin(4e-6));
                CHECK(segs[0].hi == Approx(oc.hi).margin(4e-6));
                CHECK(segs[0].nlo.present());
                CHECK(segs[0].nhi.present());
            }
        }
        CHECK(crossing > 100);
        // The midpoint rule over the dexels converges on the exact volume.
        CHECK(s.volume(axis) == Approx(f.volume()).epsilon(0.01));
    }
}
