#include "dexelmill/stock/primitive.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"

namespace dexelmill {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

/// The solid is open (method.md section 5): an interval of the line holds material only where it
/// has an interior.
bool hasInterior(const Interval& iv) { return iv.length() > 0.0; }

}  // namespace

Frustum Frustum::make(const Vec3& base, const Vec3& axis, double height, double r0, double r1) {
    const double len = glm::length(axis);
    if (!(len > 0.0) || !std::isfinite(len)) throw Error("a round stock needs a non-zero axis direction");
    if (!(height > 0.0) || !std::isfinite(height)) throw Error("a round stock needs a positive height");
    if (!(r0 >= 0.0 && r1 >= 0.0) || !std::isfinite(r0) || !std::isfinite(r1))
        throw Error("a round stock's radii must be at least 0");
    if (!(r0 > 0.0 || r1 > 0.0)) throw Error("a round stock needs a positive radius at one end at least");
    if (!std::isfinite(base.x) || !std::isfinite(base.y) || !std::isfinite(base.z))
        throw Error("a round stock's base centre must be finite");
    return {base, axis / len, height, r0, r1};
}

Box Frustum::bounds() const {
    Box b;
    const Vec3 top = base + height * axis;
    for (int i = 0; i < 3; ++i) {
        // A disc of radius r with unit normal `axis` reaches r sqrt(1 - axis_i^2) from its centre
        // along coordinate i.
        const double reach = std::sqrt(std::max(0.0, 1.0 - axis[i] * axis[i]));
        b.lo[i] = std::min(base[i] - r0 * reach, top[i] - r1 * reach);
        b.hi[i] = std::max(base[i] + r0 * reach, top[i] + r1 * reach);
    }
    return b;
}

double Frustum::volume() const { return kPi * height * (r0 * r0 + r0 * r1 + r1 * r1) / 3.0; }

FrustumChord frustumChord(const Frustum& f, const Vec3& origin, const Vec3& dir) {
    // Along the line, t(s) = t0 + k s is the height above the base face and q(s) = q0 + s m the
    // offset from the axis line. The side is |q| = r(t) = rho0 + g k s with g the radius' slope.
    const Vec3 w = origin - f.base;
    const double t0 = glm::dot(w, f.axis), k = glm::dot(dir, f.axis);
    const Vec3 q0 = w - t0 * f.axis, m = dir - k * f.axis;
    const double g = (f.r1 - f.r0) / f.height;
    const double rho0 = f.r0 + g * t0;

    // The slab between the faces: 0 < t < height. Inside it r(t) > 0, so |q| < r there is
    // Q(s) = |q|^2 - r^2 < 0, with Q(s) = A s^2 + 2 B s + C.
    Interval slab = Interval::all();
    if (k == 0.0) {
        if (!(0.0 < t0 && t0 < f.height)) return {};
    } else {
        const double sa = -t0 / k, sb = (f.height - t0) / k;
        slab = {std::min(sa, sb), std::max(sa, sb)};
    }
    const double A = glm::dot(m, m) - g * g * k * k;
    const double B = glm::dot(q0, m) - rho0 * g * k;
    const double C = glm::dot(q0, q0) - rho0 * rho0;

    Interval side = Interval::all();
    if (A == 0.0) {
        // A line along a generator of the cone (or along a cylinder's axis): Q is linear.
        if (B == 0.0) {
            if (!(C < 0.0)) return {};
        } else if (B > 0.0) {
            side.hi = -C / (2.0 * B);
        } else {
            side.lo = -C / (2.0 * B);
        }
    } else {
        const double disc = B * B - A * C;
        if (A > 0.0) {
            if (!(disc > 0.0)) return {};
            // The stable roots: no cancellation between B and the square root.
            const double qq = -(B + std::copysign(std::sqrt(disc), B));
            const double s1 = qq / A, s2 = C / qq;
            side = {std::min(s1, s2), std::max(s1, s2)};
        } else if (disc > 0.0) {
            // A < 0: Q < 0 outside the roots, the two nappes of the double cone. The slab holds
            // one nappe only (the frustum is convex), so one piece meets it; rounding can leave
            // the other touching it, and the longer piece is the chord.
            const double qq = -(B + std::copysign(std::sqrt(disc), B));
            const double s1 = qq / A, s2 = C / qq;
            const Interval before{-kInf, std::min(s1, s2)}, after{std::max(s1, s2), kInf};
            const Interval inBefore = slab.intersect(before), inAfter = slab.intersect(after);
            if (!hasInterior(inBefore) && !hasInterior(inAfter)) return {};
            side = inBefore.length() >= inAfter.length() ? before : after;
        }
        // A < 0 and disc <= 0: Q <= 0 everywhere (a line along the axis of a cone, touching the
        // surface only at the apex), and the slab decides.
    }
    const Interval chord = slab.intersect(side);
    if (!hasInterior(chord)) return {};

    FrustumChord out;
    out.empty = false;
    out.lo = chord.lo;
    out.hi = chord.hi;
    // Each end lies on a face (where the slab decides), on the side, or on the rim between them.
    auto sideNormal = [&](double s) {
        const Vec3 q = q0 + s * m;
        const double len = glm::length(q);
        if (!(len > 0.0)) return Vec3(0.0);  // the apex: no side normal; the face's is used
        return glm::normalize(q / len - g * f.axis);
    };
    auto end = [&](double s, double slabEnd, double sideEnd, Vec3& n, bool& sharp) {
        const double tHere = t0 + k * s;
        const Vec3 face = tHere < 0.5 * f.height ? -f.axis : f.axis;
        const bool onFace = std::abs(s - slabEnd) <= tol::kLength;
        const bool onSide = std::abs(s - sideEnd) <= tol::kLength;
        const Vec3 ns = onSide ? sideNormal(s) : Vec3(0.0);
        if (onSide && ns != Vec3(0.0)) {
            n = ns;
            sharp = onFace;
        } else {
            n = face;
            sharp = onSide;
        }
        // The apex of a cone is a corner, whichever constraint put the end there.
        if (f.r0 + g * tHere <= tol::kLength) sharp = true;
    };
    end(out.lo, slab.lo, side.lo, out.nlo, out.sharpLo);
    end(out.hi, slab.hi, side.hi, out.nhi, out.sharpHi);
    return out;
}

TriDexelStock stockFromFrustum(const Frustum& f, const Lattice& lattice, FamilySet families) {
    TriDexelStock stock(lattice, families);
    std::vector<Segment> segs;
    std::uint16_t counts[DexelTile::kDexels];
    for (int a = 0; a < 3; ++a) {
        const Axis axis = axisFromIndex(a);
        if (!families.has(axis)) continue;
        DexelFamily& fam = stock.family(axis);
        for (int tc = 0; tc < fam.tilesC(); ++tc) {
            for (int tb = 0; tb < fam.tilesB(); ++tb) {
                segs.clear();
                for (int i = 0; i < DexelTile::kDexels; ++i) {
                    const int ib = tb * DexelTile::kTile + i % DexelTile::kTile;
                    const int ic = tc * DexelTile::kTile + i / DexelTile::kTile;
                    counts[i] = 0;
                    if (ib >= fam.nb() || ic >= fam.nc()) continue;
                    const Line line = stock.dexelLine(axis, ib, ic);
                    const FrustumChord c = frustumChord(f, line.origin, line.dir);
                    if (c.empty || !(float(c.lo) < float(c.hi))) continue;
                    segs.push_back({float(c.lo), float(c.hi), PackedNormal::pack(c.nlo, c.sharpLo),
                                    PackedNormal::pack(c.nhi, c.sharpHi)});
                    counts[i] = 1;
                }
                fam.tile(tb, tc).assign(counts, segs.data());
            }
        }
    }
    return stock;
}

}  // namespace dexelmill
