// The Hermite data of a MoveSweep query: the outward normal at each end of a part's interval, and
// whether the end lies on a crease.
#include <algorithm>
#include <cmath>

#include "dexelmill/geometry/tolerance.h"
#include "sweep/parts.h"

namespace dexelmill {

namespace {

/// The outward unit normal of the static part (the tool at one pose) at a point x of its boundary
/// (tool frame), written to `n`. Returns whether x lies on a crease: within kCrease of a rim where
/// two of its faces meet at an angle, or of a cone's apex. There `n` is the normalised mean of the
/// two faces' normals (the axis at an apex), a normal from the crease's cone of normals.
bool staticNormal(const MoveSweep::StaticProfile& part, const Vec3& x, Vec3& n) {
    const auto& sides = part.sides;
    const double rho2 = x.x * x.x + x.y * x.y;
    // The outward unit normal of a piece's side at height z, at x's azimuth (meridianNormal). An
    // arc's is the point less its circle's centre over the radius: no root for a sphere.
    auto lateral = [&](const ProfileSide& s, double z) {
        if (s.arc && s.rc == 0.0) return Vec3(x.x, x.y, z - s.zc) * s.invRho;
        const double rho = std::sqrt(rho2);
        if (!(rho > 0.0)) return s.arc ? Vec3(0.0, 0.0, z < s.zc ? -1.0 : 1.0) : Vec3(s.nr, 0.0, s.nz);  // on the axis
        const double inv = 1.0 / rho;
        if (!s.arc) return Vec3(s.nr * inv * x.x, s.nr * inv * x.y, s.nz);
        // The circle's centre is rc across the axis in x's azimuth.
        const double out = std::max(0.0, 1.0 - s.rc * inv) * s.invRho;
        return Vec3(out * x.x, out * x.y, (z - s.zc) * s.invRho);
    };
    // The flat end face at height z (axial normal nz) whose rim `s` shares.
    auto face = [&](const EndFace& f, const ProfileSide& s, double z, double nz) {
        const Vec3 axial(0.0, 0.0, nz);
        const double inner = f.r - sweep_tol::kCrease;
        if (inner > 0.0 && rho2 <= inner * inner) {
            n = axial;
            return false;
        }
        if (!f.crease) {
            n = lateral(s, z);
            return false;
        }
        n = f.r <= sweep_tol::kCrease ? axial : glm::normalize(axial + lateral(s, z));
        return true;
    };
    if (x.z <= part.z0 + sweep_tol::kCrease) return face(part.bottomFace, sides.front(), part.z0, -1.0);
    if (x.z >= part.z1 - sweep_tol::kCrease) return face(part.topFace, sides.back(), part.z1, 1.0);
    std::size_t i = 0;
    while (i + 1 < sides.size() && x.z > sides[i].z1) ++i;
    // The joint between pieces j and j + 1, when x is on it and the slope jumps there.
    auto joint = [&](std::size_t j) {
        const double zj = sides[j].z1;
        if (!sides[j].creaseAbove || std::abs(x.z - zj) > sweep_tol::kCrease) return false;
        n = glm::normalize(lateral(sides[j], zj) + lateral(sides[j + 1], zj));
        return true;
    };
    if ((i > 0 && joint(i - 1)) || (i + 1 < sides.size() && joint(i))) return true;
    n = lateral(sides[i], x.z);
    return false;
}

/// The outward unit normal of a General move's swept volume at the point p (tool frame at the start
/// pose) of the crossing `src` of the shadow cylinder's boundary, reached at feed parameter u, feed
/// f = (fd, 0, fn), 1 / |f|^2 = invF2: the tool's normal at its grazing point p - u f, which is
/// perpendicular to f.
Vec3 crossingNormal(const MoveSweep::Part& part, const Vec3& f, double invF2, const Vec3& p, double u, Source src) {
    switch (src.kind()) {
    case Source::Strip: {
        const GrazingStrip& s = part.strips[src.index()];
        return s.normal * s.outward;
    }
    case Source::Capsule: {
        // From the sphere centre's path to p, over the radius.
        const GrazingCapsule& cap = part.capsules[src.index()];
        const Vec3 r(p.x, p.y, p.z - cap.zc);
        return (r - (glm::dot(r, f) * invF2) * f) * (1.0 / cap.rho);
    }
    case Source::Torus: {
        // From the spine circle to the grazing point.
        const GrazingTorus& t = part.tori[src.index()];
        const Vec3 g = p - u * f;
        const double rho = std::sqrt(g.x * g.x + g.y * g.y);
        const double out = rho - t.rc;
        return glm::normalize(Vec3(out * g.x, out * g.y, (g.z - t.zc) * rho));
    }
    case Source::Rim:
    default: {
        // The rim point (r cos a, r sin a, z) is p - u f. Its sine is p.e / r exactly (f has no e
        // part); its cosine comes from u, whose error is about the rounding over |n.f| (u is the
        // axial row's, (p.n - z) / fn). Each is taken where it is the better conditioned and the
        // other follows from it.
        const Circle& rim = part.rims[src.index()];
        const double fd = f.x, fn = f.z;
        const double invR = 1.0 / rim.r;
        double c = (p.x - u * fd) * invR, s = p.y * invR;
        if (std::abs(s) < std::abs(c)) c = std::copysign(std::sqrt(std::max(0.0, 1.0 - s * s)), c);
        else s = std::copysign(std::sqrt(std::max(0.0, 1.0 - c * c)), s);
        // Perpendicular to f and to the rim's tangent (-s, c, 0): in the meridian plane, fn across
        // the axis and -c fd along it; of its two senses, the one inside the rim's cone of normals.
        const double ar = fn, az = -c * fd;
        const double sense = ar * rim.nr + az * rim.nz < 0.0 ? -1.0 : 1.0;
        const double scale = sense / std::sqrt(ar * ar + az * az);
        return Vec3(ar * c * scale, ar * s * scale, az * scale);
    }
    }
}

}  // namespace

void MoveSweep::hermite(std::size_t index, const LocalLine& q, Interval local, const EndTrace& trace, unsigned ends,
                        LineHit& hit) const {
    const Part& part = parts_[index];
    const StaticProfile& profile = staticProfiles_[index];
    for (const bool hi : {false, true}) {
        if (!(ends & (hi ? kEndHi : kEndLo))) continue;
        const EndTrace::End& end = hi ? trace.hi : trace.lo;
        const Vec3 p = q.o + (hi ? local.hi : local.lo) * q.w;
        Vec3 n;  // the local normal
        bool sharp = false;
        const bool onStatic = end.pose >= 0;
        const bool atStart = !onStatic && end.u1 <= creaseU_, atEnd = !onStatic && end.u0 >= 1.0 - creaseU_;
        const bool profileNormal = onStatic || kind_ == SweepKind::Horizontal;
        if (!profileNormal) {
            if (kind_ == SweepKind::Plunge) {
                // The shadow cylinder about the axis.
                const double rho = std::sqrt(p.x * p.x + p.y * p.y);
                n = rho > 0.0 ? Vec3(p.x, p.y, 0.0) * (1.0 / rho) : Vec3(1.0, 0.0, 0.0);
            } else {
                // The crossing's normal, and the one tied with it if any.
                const EndSources& src = end.sources;
                const int count = src.second.kind() == Source::None ? 1 : 2;
                Vec3 tied[2];
                for (int j = 0; j < count; ++j)
                    tied[j] = crossingNormal(part, feedLocal_, invF2_, p, j ? src.uSecond : src.uFirst,
                                             j ? src.second : src.first);
                n = tied[0];
                if (count == 2) {
                    const Vec3 mean = tied[0] + tied[1];
                    if (glm::dot(tied[0], tied[1]) < std::cos(sweep_tol::kCreaseAngle) && glm::dot(mean, mean) > 0.0) {
                        sharp = true;
                        n = glm::normalize(mean);
                    }
                }
            }
        }
        if (profileNormal || atStart || atEnd) {
            // The static tool's normal where the end lies on it. A crossing that only the start (or
            // end) pose reaches lies on that static tool too, and the swept volume has a crease
            // there if the static tool has one (its faces meet the crossing's surface at an angle).
            // On a horizontal move, the normal at (0, p.e, p.n): seen along f, the shadow cylinder
            // is the profile at azimuth +-e with the flat faces.
            const Vec3 x = (onStatic ? end.pose == 1 : atEnd) ? p - feedLocal_
                           : onStatic || atStart                ? p
                                                                : Vec3(0.0, p.y, p.z);
            Vec3 normal;
            sharp = staticNormal(profile, x, normal) || sharp;
            if (profileNormal) n = normal;
        }
        (hi ? hit.normalHi : hit.normalLo) = n.x * frame_.d + n.y * frame_.e + n.z * frame_.n;
        (hi ? hit.sharpHi : hit.sharpLo) = sharp;
    }
}

}  // namespace dexelmill
