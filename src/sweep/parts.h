/// @file parts.h
/// @brief MoveSweep's private data: a move's convex parts as its line queries read them (the
/// grazing strips, capsules, tori and rims), the candidate ends a query collects, and the solvers
/// that sweep.cpp, torus.cpp (the tori's crossings) and normals.cpp (the Hermite data) share.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

#include <boost/container/small_vector.hpp>

#include "dexelmill/geometry/tolerance.h"
#include "dexelmill/sweep/sweep.h"

// Symbols. Everything below works in the tool frame of the move at its start pose: the origin is
// the start tip (CL point), x = d, y = e, z = n (Eq. 2), so the feed is f = (fd, 0, fn) with
// fd = d.f >= 0 and fn = n.f. A query line is o + v w in that frame. A profile piece is given by
// its height range [z0, z1] and radius R(z) (profile.h).

namespace dexelmill {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// A list that keeps up to N elements in place. A part's lists are built per move, and per node
/// of a turning move's linear search (turning.h), where allocating them cost more than the
/// geometry (BM_SweepBuild). The sizes hold what a turning move's nodes need (cones and
/// cylinders, a ball's capsule); longer lists, and the rarer kinds (tori, a horizontal move's
/// faces), go to the heap, so that a kept node stays small.
template <class T, std::size_t N>
using InlineList = boost::container::small_vector<T, N>;

/// The slope dR/dz of a cone piece.
inline double coneSlope(const ConePiece& c) { return (c.r1 - c.r0) / (c.z1 - c.z0); }

/// A generator segment O + t S (t in [0, 1]) of a cone or cylinder that grazes, with N = S x f.
struct GrazingStrip {
    Vec3 origin{0.0};
    Vec3 span{0.0};
    Vec3 normal{0.0};
    double outward = 0.0;     ///< normal * outward is the cone's outward unit normal along the generator
    double degenerate = 0.0;  ///< |w . N| at or below this: the line is parallel to the strip
};

/// The grazing great circle of a sphere piece, swept: a cylinder of radius rho about the line
/// through (0, 0, zc) along f, clipped to the piece's heights.
struct GrazingCapsule {
    double zc = 0.0, rho = 0.0, z0 = 0.0, z1 = 0.0;
};

/// One of the two mirror arcs of a torus piece's grazing curve, psi = psiMid + 2 atan(t),
/// t in [-T, T], where psi is the angle of the grazing normal N(psi) = cos(psi) q + sin(psi) e,
/// q = (-fn, 0, fd) / |f| (both perpendicular to f).
struct TorusArc {
    double cosMid = 1.0, sinMid = 0.0, T = 0.0;
    double side = 1.0;     ///< +1: psi in [0, pi] (e . N >= 0); -1: psi in [-pi, 0]
    Vec3 endLo{0.0};       ///< grazing point at t = -T
    Vec3 endHi{0.0};       ///< grazing point at t = +T
};

/// The grazing curve of a torus piece (rc > 0) on an ascending or descending move.
struct GrazingTorus {
    double rc = 0.0, zc = 0.0, rho = 0.0;
    double cosLo = -1.0, cosHi = 1.0;  ///< cos(psi) range of the arcs (heights within the piece)
    int arcs = 0;
    TorusArc arc[2];
};

/// A circle at height z, radius r where two faces meet at an angle (or a flat face of a
/// horizontal move, as a disk). For a rim, qc = fd z / |f| is the centre of its swept ellipse
/// along q (see the rims in intersectLocal), and (nr, nz) is a direction inside its cone of normals
/// in the meridian plane (across the axis, along it): the sum of the two faces' unit normals.
struct Circle {
    double z = 0.0, r = 0.0, qc = 0.0;
    double nr = 0.0, nz = 0.0;
};

/// Where a crossing of a line with the boundary of a General move's shadow cylinder came from, so
/// that the normal there can be found for the ends of the interval only: the kind of crossing and
/// its index in the part's list of that kind, in one word (a traced query stores one per candidate
/// end it finds).
struct Source {
    enum Kind : std::uint32_t { Strip, Capsule, Torus, Rim, None };
    std::uint32_t code;

    static constexpr Source of(Kind kind, std::uint32_t index) { return {std::uint32_t(kind) << 24 | index}; }
    Kind kind() const { return Kind(code >> 24); }
    std::uint32_t index() const { return code & 0xFFFFFFu; }
};

/// No crossing: plunges and horizontal moves need none for their normals, and a crossing tied with
/// no other has none beside it.
constexpr Source kNoSource = Source::of(Source::None, 0);

/// The crossings found at one end of an interval, each with the feed parameter that reaches it:
/// the first, and the last other one that tied with it (within kTie), or kNoSource. Tied crossings
/// may be reached at very different feed parameters (on a nearly plunging move, the sweeps of a
/// rim and of a torus's equator of the same radius nearly coincide). Left uninitialised by default
/// (as is MoveSweep::EndTrace): a traced query writes what its ends use, and the Interval queries
/// never build one.
struct EndSources {
    Source first, second;
    double uFirst, uSecond;
};

/// A profile piece's side as the static tool's normals need it (staticNormal): its top height, a
/// cone's meridian unit normal (across the axis, along it) or an arc's circle centre, and whether
/// the slope jumps where the next piece starts (a rim).
struct ProfileSide {
    double z1 = 0.0;
    bool arc = false;
    double nr = 0.0, nz = 0.0;
    double rc = 0.0, zc = 0.0, invRho = 0.0;  ///< an arc's circle: centre, 1 / radius
    bool creaseAbove = false;
};

/// A part's flat end face for the static tool's normals: its radius, and whether it meets the side
/// at an angle (a rim, or an apex when the radius is 0).
struct EndFace {
    double r = 0.0;
    bool crease = false;
};

/// A convex part of the tool as its static normals need it (staticNormal): its heights, its pieces'
/// sides and its end faces. Kept apart from MoveSweep::Part, which the Interval queries read.
struct MoveSweep::StaticProfile {
    /// User-provided, so that emplace_back() does not zero the inline list's storage first.
    StaticProfile() {}
    double z0 = 0.0, z1 = 0.0;
    InlineList<ProfileSide, 4> sides;
    EndFace bottomFace, topFace;
};

struct MoveSweep::Part {
    /// User-provided, so that emplace_back() does not zero the inline lists' storage first.
    Part() {}
    InlineList<ProfilePiece, 4> pieces;  ///< for the static tool
    double z0 = 0.0, z1 = 0.0;
    // Plunge: the cylinder of the largest radius, reached on heights [zMax0, zMax1].
    double rMax = 0.0, zMax0 = 0.0, zMax1 = 0.0;
    // General and horizontal moves.
    InlineList<GrazingStrip, 6> strips;
    InlineList<GrazingCapsule, 1> capsules;  // general moves
    InlineList<GrazingTorus, 0> tori;        // general moves
    InlineList<Circle, 4> rims;              // general moves
    InlineList<ArcPiece, 0> meridianArcs;    // horizontal moves
    InlineList<Circle, 0> disks;             // horizontal moves
    /// The heights where R(z) >= r, one interval since R is concave on the part.
    Interval widerThan(double r) const {
        Interval z;
        for (const ProfilePiece& p : pieces) {
            if (const auto* c = std::get_if<ConePiece>(&p)) {
                if (std::max(c->r0, c->r1) < r) continue;
                // R = r0 + k (z - z0) >= r on the piece.
                Interval piece{c->z0, c->z1};
                if (c->r1 > c->r0) piece.lo = std::max(c->z0, c->z0 + (r - c->r0) / coneSlope(*c));
                else if (c->r1 < c->r0) piece.hi = std::min(c->z1, c->z0 + (r - c->r0) / coneSlope(*c));
                z = z.hull(piece);
            } else {
                const ArcPiece& a = std::get<ArcPiece>(p);
                const double out = r - a.rc;
                if (out > a.rho) continue;
                const double half = out <= 0.0 ? a.rho : std::sqrt(a.rho * a.rho - out * out);
                const Interval piece = Interval{a.z0, a.z1}.intersect({a.zc - half, a.zc + half});
                if (!piece.isEmpty()) z = z.hull(piece);
            }
        }
        return z;
    }
    /// The swept part's extent along each of MoveSweep::boxAxes_ (coordinates from the start tip):
    /// an oriented box holding the sweep.
    Interval box[3];
};

/// A query line in the move's frame, with the per-line quantities every part shares.
/// Where the two ends of a part's interval lie (intersectLocal<true>), for hermite.
struct MoveSweep::EndTrace {
    struct End {
        int pose;            ///< 0 or 1: on the static tool at the start or end pose; -1: a crossing
        EndSources sources;  ///< General moves: the crossings found there
        double u0, u1;       ///< the feed parameters that put a tool point on the crossing
    };
    End lo, hi;
};

/// The candidate ends of a line's interval in the shadow cylinder: the lowest and highest line
/// parameters found on its boundary, each with the range of feed parameters u that put a tool
/// point there. With kTrace, also where each came from, recorded in `lo` and `hi` (the Interval
/// queries keep no sources).
template <bool kTrace>
struct Extremes {
    struct NoSources {};
    using Sources = std::conditional_t<kTrace, EndSources*, NoSources>;

    double vLo = kInf, vHi = -kInf;
    double loU0 = 0.0, loU1 = 0.0, hiU0 = 0.0, hiU1 = 0.0;
    Sources lo{}, hi{};

    bool empty() const { return vLo > vHi; }
    void add(double v, double u0, double u1, const Source& src) {
        if (v < vLo - sweep_tol::kTie) {
            vLo = v, loU0 = u0, loU1 = u1;
            if constexpr (kTrace) lo->first = src, lo->uFirst = u0, lo->second = kNoSource;
        } else if (v <= vLo + sweep_tol::kTie) {
            vLo = std::min(vLo, v), loU0 = std::min(loU0, u0), loU1 = std::max(loU1, u1);
            if constexpr (kTrace) lo->second = src, lo->uSecond = u0;
        }
        if (v > vHi + sweep_tol::kTie) {
            vHi = v, hiU0 = u0, hiU1 = u1;
            if constexpr (kTrace) hi->first = src, hi->uFirst = u0, hi->second = kNoSource;
        } else if (v >= vHi - sweep_tol::kTie) {
            vHi = std::max(vHi, v), hiU0 = std::min(hiU0, u0), hiU1 = std::max(hiU1, u1);
            if constexpr (kTrace) hi->second = src, hi->uSecond = u0;
        }
    }
    void add(double v, double u, const Source& src) { add(v, u, u, src); }
};

/// The grazing point of a torus (rc, zc, rho) with outward normal N, Nr = |N projected on the
/// plane perpendicular to the axis| > 0: the spine point in N's azimuth plus rho N (Eq. 21).
inline Vec3 torusPoint(const GrazingTorus& t, double nx, double ny, double nz) {
    const double k = t.rc / std::sqrt(nx * nx + ny * ny) + t.rho;
    return {k * nx, k * ny, t.zc + t.rho * nz};
}

/// The query quantities the torus solver needs: the local line, c = w x f, |c|^2, c . o, f.
struct TorusLine {
    Vec3 o, w, c;
    double c2, co;
    Vec3 f;
};

/// Adds the crossings of the line with a torus piece's grazing surface to `ex` (torus.cpp, where
/// the method is). Instantiated for Extremes<false> and Extremes<true>.
template <class Ex>
void torusCrossings(const GrazingTorus& tor, std::uint32_t index, const TorusLine& l, Ex& ex);

}  // namespace dexelmill
