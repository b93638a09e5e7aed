#include "dexelmill/sweep/sweep.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include <boost/math/tools/toms748_solve.hpp>

#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"

// Symbols. Everything below works in the tool frame of the move at its start pose: the origin is
// the start tip (CL point), x = d, y = e, z = n (Eq. 2), so the feed is f = (fd, 0, fn) with
// fd = d.f >= 0 and fn = n.f. A query line is o + v w in that frame. A profile piece is given by
// its height range [z0, z1] and radius R(z) (profile.h).

namespace dexelmill {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// Real roots of a v^2 + 2 b v + c = 0 (numerically stable form). Returns how many (0, 1 or 2).
int quadraticRoots(double a, double b, double c, double& r1, double& r2) {
    if (a == 0.0) {
        if (b == 0.0) return 0;
        r1 = r2 = -c / (2.0 * b);
        return 1;
    }
    const double disc = b * b - a * c;
    if (disc < 0.0) return 0;
    const double q = -(b + std::copysign(std::sqrt(disc), b));
    if (q == 0.0) {  // b == 0 and c == 0: a double root at 0
        r1 = r2 = 0.0;
        return 2;
    }
    r1 = q / a;
    r2 = c / q;
    return 2;
}

double coneSlope(const ConePiece& c) { return (c.r1 - c.r0) / (c.z1 - c.z0); }

/// True when an arc piece ends (at height z) where its tangent is horizontal in the profile,
/// i.e. where its surface normal is the axis: a flat face there joins it without a kink.
bool arcEndIsFlat(const ArcPiece& a, double z) {
    return std::abs(std::abs(z - a.zc) - a.rho) <= tol::kProfileJoint;
}

/// True when a flat face at height z (the piece's lowest or highest) meets the piece at an angle:
/// a rim, or a cone's apex when the piece's radius there is 0.
bool faceMeetsAtAngle(const ProfilePiece& piece, double z) {
    const auto* a = std::get_if<ArcPiece>(&piece);
    return !(a && arcEndIsFlat(*a, z));
}

/// True when the slope of the profile jumps at height zj, where `below` ends and `above` starts.
bool slopeJumps(const ProfilePiece& below, const ProfilePiece& above, double zj) {
    const double sBelow = pieceSlope(below, zj), sAbove = pieceSlope(above, zj);
    return std::abs(sBelow - sAbove) > tol::kSlope * std::max(1.0, std::abs(sBelow));
}

}  // namespace

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
    double z0 = 0.0, z1 = 0.0;
    std::vector<ProfileSide> sides;
    EndFace bottomFace, topFace;
};

struct MoveSweep::Part {
    std::vector<ProfilePiece> pieces;  ///< for the static tool
    double z0 = 0.0, z1 = 0.0;
    // Plunge: the cylinder of the largest radius, reached on heights [zMax0, zMax1].
    double rMax = 0.0, zMax0 = 0.0, zMax1 = 0.0;
    // General and horizontal moves.
    std::vector<GrazingStrip> strips;
    std::vector<GrazingCapsule> capsules;  // general moves
    std::vector<GrazingTorus> tori;        // general moves
    std::vector<Circle> rims;              // general moves
    std::vector<ArcPiece> meridianArcs;    // horizontal moves
    std::vector<Circle> disks;             // horizontal moves
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

namespace {

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

/// The tool-frame line coefficients of the foundation's static queries (tool.h): height
/// z0 + zv t, squared axis distance A t^2 + 2 B t + C, with t the local line parameter.
LocalLine localLine(const Vec3& o, const Vec3& w) {
    LocalLine l;
    l.z0 = o.z;
    l.zv = w.z;
    l.A = w.x * w.x + w.y * w.y;
    l.B = o.x * w.x + o.y * w.y;
    l.C = o.x * o.x + o.y * o.y;
    l.vShift = 0.0;
    return l;
}

/// The line o + v w inside the static part (the tool at one pose): the hull of its pieces'
/// intervals, which is exact because the part is convex.
Interval staticPart(const MoveSweep::Part& part, const Vec3& o, const Vec3& w) {
    const LocalLine l = localLine(o, w);
    Interval hull;
    for (const ProfilePiece& p : part.pieces) hull = hull.hull(intersectPiece(p, l));
    return hull;
}

/// Support value max over the part of (z xn + R(z) xr): the part's extent in a direction with
/// axial component xn and radial component xr >= 0, measured from the tip.
double partSupport(const std::vector<ProfilePiece>& pieces, double xn, double xr) {
    double h = -kInf;
    for (const ProfilePiece& p : pieces) {
        if (const auto* c = std::get_if<ConePiece>(&p)) {
            h = std::max({h, c->z0 * xn + c->r0 * xr, c->z1 * xn + c->r1 * xr});
        } else {
            const ArcPiece& a = std::get<ArcPiece>(p);
            // On the arc the outward normal (xr, xn) is reached at z = zc + rho xn.
            const double len = std::hypot(xn, xr);
            const double z = std::clamp(a.zc + a.rho * xn / len, a.z0, a.z1);
            h = std::max(h, z * xn + pieceRadius(p, z) * xr);
        }
    }
    return h;
}

/// The grazing point of a torus (rc, zc, rho) with outward normal N, Nr = |N projected on the
/// plane perpendicular to the axis| > 0: the spine point in N's azimuth plus rho N (Eq. 21).
inline Vec3 torusPoint(const GrazingTorus& t, double nx, double ny, double nz) {
    const double k = t.rc / std::sqrt(nx * nx + ny * ny) + t.rho;
    return {k * nx, k * ny, t.zc + t.rho * nz};
}


/// A root of a function monotone on [a, b] whose values ga = g(a) and gb = g(b) are of opposite
/// signs and not zero: Newton's method with the analytic slope, safeguarded by the sign-change
/// bracket. A Newton step is taken only when it lands strictly inside the bracket and is at most
/// half the step before it; otherwise the bracket is bisected. The first point is `t0` when it
/// lies strictly inside the bracket, else the secant (regula falsi) point. Stops when a step or the
/// bracket is at most `tol`, or when two Newton steps in a row show quadratic convergence that puts
/// the next step below `tol` (the error after a Newton step of size s is about (s / s_before^2) s^2).
/// `gd(t, slope)` returns g(t) and writes g'(t).
///
/// Why not Boost's newton_raphson_iterate (1.74, Debian 12): it moves its bracket by the sign of
/// the Newton step g / g' rather than of g, and raises an error when the two disagree. Near a
/// tangent line the root sits next to an extremum of g, where g' rounds to either sign; a bracket
/// kept by the sign of g, as here, stays valid there. TOMS 748 (Boost) solves the same brackets
/// without the slope; when this replaced it, callgrind counted 2,218 instructions per bull-nose
/// ramp query with TOMS 748 against 1,521 with it.
template <class GD>
double bracketedNewton(GD&& gd, double a, double b, double ga, double gb, double t0, double tol) {
    constexpr int kMaxSteps = 100;  // bisection alone halves a bracket of width 2 to 1e-13 in 45
    double neg = ga < 0.0 ? a : b, pos = ga < 0.0 ? b : a;  // g(neg) < 0 < g(pos)
    double t = t0;
    if (!(t > std::min(a, b) && t < std::max(a, b))) t = a - ga * (b - a) / (gb - ga);
    if (!(t > std::min(a, b) && t < std::max(a, b))) t = 0.5 * (a + b);
    double step = std::abs(b - a), stepBefore = 2.0 * step;
    bool newtonBefore = false;
    for (int i = 0; i < kMaxSteps; ++i) {
        double slope;
        const double g = gd(t, slope);
        if (g == 0.0) return t;
        (g < 0.0 ? neg : pos) = t;
        const double newton = t - g / slope;
        const bool inside = slope != 0.0 && newton > std::min(neg, pos) && newton < std::max(neg, pos);
        stepBefore = step;
        const bool isNewton = inside && 2.0 * std::abs(g) <= std::abs(stepBefore * slope);
        if (isNewton) {
            step = std::abs(newton - t);
            t = newton;
            if (newtonBefore && step * step * step <= tol * stepBefore * stepBefore) return t;
        } else {
            t = 0.5 * (neg + pos);
            step = 0.5 * std::abs(pos - neg);
        }
        newtonBefore = isNewton;
        if (step <= tol || std::abs(pos - neg) <= tol) return t;
    }
    return t;
}

/// The query quantities the torus solver needs: the local line, c = w x f, |c|^2, c . o, f.
struct TorusLine {
    Vec3 o, w, c;
    double c2, co;
    Vec3 f;
};

/// Adds the crossings of the line with a torus piece's grazing surface to `ex`.
///
/// Eq. (36): the line meets the sweep of the grazing point G where g = c . (G - o) = 0,
/// c = w x f. Seen along f, the grazing curve is the outline of the torus's shadow and g is the
/// signed distance of its points from the projected line, times |c|. Along that convex outline g
/// has exactly one maximum, where the grazing normal is c / |c|, and one minimum (-c / |c|): so
/// each arc, split at those two points, falls into pieces where g is monotone and every root is
/// bracketed by a sign change. That is Algorithm 1 with its extremum (fminbnd in the paper) in
/// closed form; the roots are found by Newton's method on the bracket (bracketedNewton), with
/// TOMS 748 in the spine chart.
///
/// Two charts of the curve keep the root finder well conditioned:
///  - the normal angle psi, N(psi) = cos(psi) q + sin(psi) e, on most of the curve;
///  - the spine angle s (the paper's parameter, Eq. 34), N(s) ~ (|fn| cos s, |fn| sin s,
///    -sign(fn) fd cos s), near the d-n plane, on moves with kappa = |fn| / |f| < kSpineChart.
///    On a nearly horizontal move that stretch of the curve runs along the torus's bottom (or
///    top) circle but is squeezed into a psi-window of width about kappa: the spine azimuth s
///    turns by cos^2(s) / kappa per unit of psi. The charts meet where |sin psi| = sqrt(kappa)
///    |cos psi|, at |cos s| = sqrt(kappa) (about): there s turns by about one unit per unit of
///    psi, and the grazing point's climb up the torus as |cos s| falls, rho kappa / cos^2(s) per
///    unit of s, is at most about rho. With the charts meeting at 45 degrees instead, a root found to
///    kAngleRoot in psi was off by kAngleRoot / (2 kappa) in s: 2e-6 mm at kappa = 5e-9.
template <class Ex>
void torusCrossings(const GrazingTorus& tor, std::uint32_t index, const TorusLine& l, Ex& ex) {
    const double fd = l.f.x, fn = l.f.z;
    const double flen = std::sqrt(fd * fd + fn * fn);
    const double kappa = std::abs(fn) / flen;
    const Vec3 qDir(-fn / flen, 0.0, fd / flen);
    const double cLen = std::sqrt(l.c2);
    const double cq = glm::dot(l.c, qDir) / cLen, ce = l.c.y / cLen;  // c / |c| = cq q + ce e
    const double sgnFn = fn > 0.0 ? 1.0 : -1.0;

    // The crossing (v, u) of the line with the sweep of the grazing point G:
    // G - o = v w - u f, so v = ((G - o) x f) . c / |c|^2 and u = ((G - o) x w) . c / |c|^2.
    auto addCrossing = [&](const Vec3& g) {
        const Vec3 go = g - l.o;
        ex.add(glm::dot(glm::cross(go, l.f), l.c) / l.c2, glm::dot(glm::cross(go, l.w), l.c) / l.c2,
               Source::of(Source::Torus, index));
    };
    const auto stop = [](double a, double b) { return std::abs(b - a) <= sweep_tol::kAngleRoot; };
    // A root of a monotone piece of g on [a, b] (values ga, gb), or nothing.
    auto solve = [&](auto&& g, double a, double b, double ga, double gb, double& root) {
        if (ga == 0.0) return root = a, true;
        if (gb == 0.0) return root = b, true;
        if ((ga < 0.0) == (gb < 0.0)) return false;
        boost::uintmax_t iters = 80;
        const auto br = boost::math::tools::toms748_solve(g, a, b, ga, gb, stop, iters);
        root = 0.5 * (br.first + br.second);
        return true;
    };
    // Spine chart: the grazing point at the azimuth (cs, ss) of its normal (a unit vector).
    auto spinePoint = [&](double cs, double ss) {
        const double inv = 1.0 / std::sqrt(fn * fn + fd * fd * cs * cs);
        const double nr = std::abs(fn) * inv;
        return Vec3((tor.rc + tor.rho * nr) * cs, (tor.rc + tor.rho * nr) * ss,
                    tor.zc - sgnFn * tor.rho * fd * cs * inv);
    };
    const bool useSpine = kappa < sweep_tol::kSpineChart;
    const double chartSlope = std::sqrt(kappa);  // the charts meet where |sin psi| = this |cos psi|
    for (int k = 0; k < tor.arcs; ++k) {
        const TorusArc& arc = tor.arc[k];
        // Normal-angle chart: psi = psiMid + 2 atan(t).
        auto normal = [&](double t, double& cp, double& sp) {
            const double t2 = t * t, den = 1.0 / (1.0 + t2);
            const double cd = (1.0 - t2) * den, sd = 2.0 * t * den;
            cp = arc.cosMid * cd - arc.sinMid * sd;
            sp = arc.sinMid * cd + arc.cosMid * sd;
        };
        auto point = [&](double t) {
            double cp, sp;
            normal(t, cp, sp);
            return torusPoint(tor, -fn * cp / flen, sp, fd * cp / flen);
        };
        auto g = [&](double t) { return glm::dot(l.c, point(t)) - l.co; };
        // g and dg/dt: with dpsi/dt = 2 / (1 + t^2), the grazing point P = k Nxy + (0, 0, zc + rho Nz)
        // (k = rc / |Nxy| + rho, Nxy the normal's part across the axis) moves by
        // dP/dpsi = dk Nxy + k dNxy/dpsi + rho dNz/dpsi, dk = -rc (Nxy . dNxy/dpsi) / |Nxy|^3.
        auto gSlope = [&](double t, double& slope) {
            double cp, sp;
            normal(t, cp, sp);
            const double nx = -fn * cp / flen, nz = fd * cp / flen;
            const double dnx = fn * sp / flen, dnz = -fd * sp / flen;  // dny/dpsi = cp
            const double nr2 = nx * nx + sp * sp, nr = std::sqrt(nr2);
            const double k = tor.rc / nr + tor.rho;
            const double dk = -tor.rc * (nx * dnx + sp * cp) / (nr2 * nr);
            const Vec3 p(k * nx, k * sp, tor.zc + tor.rho * nz);
            const Vec3 dp(dk * nx + k * dnx, dk * sp + k * cp, tor.rho * dnz);
            slope = glm::dot(l.c, dp) * 2.0 / (1.0 + t * t);
            return glm::dot(l.c, p) - l.co;
        };
        // t of a normal direction (cos psi, sin psi) inside the arc.
        auto tOf = [&](double cx, double sy) {
            const double cosD = cx * arc.cosMid + sy * arc.sinMid;
            const double sinD = sy * arc.cosMid - cx * arc.sinMid;
            return std::clamp(sinD / (1.0 + cosD), -arc.T, arc.T);
        };
        auto inArc = [&](double cx, double sy) {
            return arc.side * sy >= 0.0 && cx >= tor.cosLo && cx <= tor.cosHi;
        };

        // Split points: the extrema of g (N = +-c/|c|) and the chart boundaries |sin psi| =
        // sqrt(kappa) |cos psi|.
        double ts[6];
        bool extremum[6] = {};
        int m = 0;
        ts[m++] = -arc.T;
        for (double sgn : {1.0, -1.0})
            if (inArc(sgn * cq, sgn * ce)) extremum[m] = true, ts[m++] = tOf(sgn * cq, sgn * ce);
        if (useSpine) {
            const double cw = 1.0 / std::sqrt(1.0 + chartSlope * chartSlope), sw = chartSlope * cw;
            for (double sgn : {1.0, -1.0})
                if (inArc(sgn * cw, arc.side * sw)) ts[m++] = tOf(sgn * cw, arc.side * sw);
        }
        ts[m++] = arc.T;
        for (int i = 2; i + 1 < m; ++i)  // insertion sort of the (at most 4) inner points
            for (int j = i; j > 1 && ts[j - 1] > ts[j]; --j) {
                std::swap(ts[j - 1], ts[j]);
                std::swap(extremum[j - 1], extremum[j]);
            }

        // A first guess at the root of a piece from an extremum te of g (value ge) to tb (value
        // gb): fit g = A + B cos(psi - psi_e), exact for a sphere's outline (a circle) and close
        // for a torus's, and solve it. Not a bracket: bracketedNewton checks it lies inside.
        auto fittedRoot = [&](double te, double tb, double ge, double gb) {
            double ce0, se0, cb0, sb0;
            normal(te, ce0, se0);
            normal(tb, cb0, sb0);
            const double cosD = ce0 * cb0 + se0 * sb0, sinD = ce0 * sb0 - se0 * cb0;
            const double B = (ge - gb) / (1.0 - cosD);
            const double cr = std::clamp((B - ge) / B, -1.0, 1.0);  // cos(psi_root - psi_e) = -A / B
            const double sr = std::copysign(std::sqrt(1.0 - cr * cr), sinD);
            return tOf(ce0 * cr - se0 * sr, se0 * cr + ce0 * sr);
        };

        double gPrev = glm::dot(l.c, arc.endLo) - l.co;
        for (int i = 0; i + 1 < m; ++i) {
            const double ta = ts[i], tb = ts[i + 1];
            const double gb = i + 2 == m ? glm::dot(l.c, arc.endHi) - l.co : g(tb);
            const double ga = gPrev;
            gPrev = gb;
            if (!(tb > ta) && !(ga == 0.0)) continue;
            double cp, sp;
            normal(0.5 * (ta + tb), cp, sp);
            const bool spineChart = useSpine && std::abs(sp) < chartSlope * std::abs(cp);
            double root;
            if (!spineChart) {
                if (ga == 0.0) {
                    addCrossing(point(ta));
                } else if (gb == 0.0) {
                    addCrossing(point(tb));
                } else if ((ga < 0.0) != (gb < 0.0)) {
                    const double t0 = extremum[i]       ? fittedRoot(ta, tb, ga, gb)
                                      : extremum[i + 1] ? fittedRoot(tb, ta, gb, ga)
                                                        : kInf;
                    addCrossing(point(bracketedNewton(gSlope, ta, tb, ga, gb, t0, sweep_tol::kAngleRoot)));
                }
                continue;
            }
            // The same stretch in the spine chart, parametrised without trigonometry by the
            // direction a(tau) ~ a0 + tau (a1 - a0), tau in [0, 1], between the azimuths a0, a1 of
            // the normals at its ends (less than 90 degrees apart, so a is monotone in angle).
            // The bracket keeps the values of g the neighbouring pieces saw at its ends.
            double c0, s0, c1, s1;
            normal(ta, c0, s0);
            normal(tb, c1, s1);
            const double ax0 = -fn * c0 / flen, ay0 = arc.side * std::abs(s0);
            const double ax1 = -fn * c1 / flen, ay1 = arc.side * std::abs(s1);
            auto spineAt = [&](double tau) {
                const double x = ax0 + tau * (ax1 - ax0), y = ay0 + tau * (ay1 - ay0);
                const double inv = 1.0 / std::sqrt(x * x + y * y);
                return spinePoint(x * inv, y * inv);
            };
            auto gSpine = [&](double tau) { return glm::dot(l.c, spineAt(tau)) - l.co; };
            if (solve(gSpine, 0.0, 1.0, ga, gb, root)) addCrossing(spineAt(root));
        }
    }
}

/// The outward unit normal of the static part (the tool at one pose) at a point x of its boundary
/// (tool frame), written to `n`. Returns whether x lies on a crease: within kCrease of a rim where
/// two of its faces meet at an angle, or of a cone's apex. There `n` is the normalised mean of the
/// two faces' normals (the axis at an apex), a normal from the crease's cone of normals.
bool staticNormal(const MoveSweep::StaticProfile& part, const Vec3& x, Vec3& n) {
    const std::vector<ProfileSide>& sides = part.sides;
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

MoveSweep::MoveSweep(const Tool& tool, const Move& move) : MoveSweep(tool, move.start, move.end, move.axis) {}

MoveSweep::MoveSweep(const MoveSweep&) = default;
MoveSweep::MoveSweep(MoveSweep&&) noexcept = default;
MoveSweep& MoveSweep::operator=(const MoveSweep&) = default;
MoveSweep& MoveSweep::operator=(MoveSweep&&) noexcept = default;
MoveSweep::~MoveSweep() = default;

std::size_t MoveSweep::partCount() const { return parts_.size(); }

MoveSweep::MoveSweep(const Tool& tool, const Vec3& start, const Vec3& end, const Vec3& axis)
    : start_(start) {
    const Vec3 f = end - start;
    frame_ = ToolFrame::make(axis, f);  // validates the axis
    if (tool.convexParts().size() > kMaxParts)
        throw Error("tool '" + tool.description() + "' has " + std::to_string(tool.convexParts().size()) +
                    " convex parts; the sweep handles at most " + std::to_string(kMaxParts));
    feedLength_ = glm::length(f);
    creaseU_ = sweep_tol::kCrease / feedLength_;
    const Vec3& n = frame_.n;
    const double fn = glm::dot(f, n);
    if (feedLength_ <= tol::kZeroMove) {
        kind_ = SweepKind::Static;
        feedLocal_ = Vec3(0.0);
    } else if (frame_.plunge) {
        kind_ = SweepKind::Plunge;
        feedLocal_ = Vec3(0.0, 0.0, fn);
    } else {
        // d.f as the length of f's part perpendicular to n (d is that part normalised): dotting f
        // itself with d would add (n.f)(n.d), a rounding error large against a tiny d.f.
        const double fd = glm::dot(f - fn * n, frame_.d);
        if (std::abs(fn) <= sweep_tol::kHorizontal * feedLength_) {
            kind_ = SweepKind::Horizontal;
            feedLocal_ = Vec3(fd, 0.0, 0.0);
        } else {
            kind_ = SweepKind::General;
            feedLocal_ = Vec3(fd, 0.0, fn);
        }
    }
    const double fd = feedLocal_.x, fnl = feedLocal_.z;
    const double flen = glm::length(feedLocal_);
    if (kind_ == SweepKind::General) {
        invF2_ = 1.0 / (flen * flen);
        invFn_ = 1.0 / fnl;
        kappa_ = std::abs(fnl) / flen;
        qDir_ = Vec3(-fnl / flen, 0.0, fd / flen);
    }
    // A rim at height z, radius r between faces with meridian unit normals (nr0, nz0) below and
    // (nr1, nz1) above.
    const auto rimAt = [&](double z, double r, double nr0, double nz0, double nr1, double nz1) {
        return Circle{z, r, fd * z / flen, nr0 + nr1, nz0 + nz1};
    };
    const auto sideNormal = [](const ProfilePiece& p, double z, double& nr, double& nz) {
        meridianNormal(p, pieceRadius(p, z), z, nr, nz);
    };

    for (const ConvexPart& cp : tool.convexParts()) {
        Part part;
        part.pieces.assign(tool.pieces().begin() + std::ptrdiff_t(cp.first),
                           tool.pieces().begin() + std::ptrdiff_t(cp.last));
        part.z0 = cp.z0;
        part.z1 = cp.z1;
        const ProfilePiece& bottom = part.pieces.front();
        const ProfilePiece& top = part.pieces.back();
        const double rBottom = pieceRadius(bottom, part.z0), rTop = pieceRadius(top, part.z1);
        StaticProfile& profile = staticProfiles_.emplace_back();
        profile.z0 = part.z0, profile.z1 = part.z1;
        for (std::size_t i = 0; i < part.pieces.size(); ++i) {
            const ProfilePiece& p = part.pieces[i];
            ProfileSide side;
            side.z1 = pieceZ1(p);
            if (const auto* a = std::get_if<ArcPiece>(&p))
                side.arc = true, side.rc = a->rc, side.zc = a->zc, side.invRho = 1.0 / a->rho;
            else meridianNormal(p, 0.0, 0.0, side.nr, side.nz);
            side.creaseAbove = i + 1 < part.pieces.size() && slopeJumps(p, part.pieces[i + 1], side.z1);
            profile.sides.push_back(side);
        }
        profile.bottomFace = {rBottom, faceMeetsAtAngle(bottom, part.z0)};
        profile.topFace = {rTop, faceMeetsAtAngle(top, part.z1)};

        // The largest radius and the heights where it is reached (R is concave: an interval).
        part.rMax = -kInf;
        for (const ProfilePiece& p : part.pieces) {
            const double pz0 = pieceZ0(p), pz1 = pieceZ1(p);
            double zPeak0, zPeak1, r;
            if (const auto* c = std::get_if<ConePiece>(&p)) {
                if (c->r0 == c->r1) zPeak0 = pz0, zPeak1 = pz1, r = c->r0;
                else if (c->r0 > c->r1) zPeak0 = zPeak1 = pz0, r = c->r0;
                else zPeak0 = zPeak1 = pz1, r = c->r1;
            } else {
                const ArcPiece& a = std::get<ArcPiece>(p);
                zPeak0 = zPeak1 = std::clamp(a.zc, pz0, pz1);
                r = pieceRadius(p, zPeak0);
            }
            const double same = tol::kLength * std::max(1.0, r);
            if (r > part.rMax + same) {
                part.rMax = r, part.zMax0 = zPeak0, part.zMax1 = zPeak1;
            } else if (r >= part.rMax - same) {
                part.rMax = std::max(part.rMax, r);
                part.zMax0 = std::min(part.zMax0, zPeak0), part.zMax1 = std::max(part.zMax1, zPeak1);
            }
        }

        if (kind_ == SweepKind::General || kind_ == SweepKind::Horizontal) {
            // Cones and cylinders: Eq. (28), the generators at azimuth phi with
            // cos(phi) = k (n.f) / (d.f) graze (k = dR/dz); Eq. (30), each sweeps the planar strip
            // O + t S + u f. Horizontal moves: cos(phi) = 0, the generators at +-e.
            for (const ProfilePiece& p : part.pieces) {
                const auto* c = std::get_if<ConePiece>(&p);
                if (!c) continue;
                const double cosPhi = coneSlope(*c) * fnl / fd;
                if (std::abs(cosPhi) > 1.0) continue;  // no generator grazes: steeper than the flank
                const double sinPhi = std::sqrt(std::max(0.0, 1.0 - cosPhi * cosPhi));
                for (double sgn : {1.0, -1.0}) {
                    GrazingStrip s;
                    const Vec3 radial(cosPhi, sgn * sinPhi, 0.0);
                    s.origin = c->r0 * radial + Vec3(0.0, 0.0, c->z0);
                    s.span = (c->r1 - c->r0) * radial + Vec3(0.0, 0.0, c->z1 - c->z0);
                    s.normal = glm::cross(s.span, feedLocal_);
                    // The cone's outward normal (radial, -dR/dz) is perpendicular to S and f.
                    s.outward = (glm::dot(s.normal, radial) < 0.0 ? -1.0 : 1.0) / glm::length(s.normal);
                    s.degenerate = tol::kParallel * glm::length(s.span) * flen;
                    if (glm::length(s.normal) > s.degenerate) part.strips.push_back(s);
                    if (sinPhi == 0.0) break;  // a single generator
                }
            }
        }

        if (kind_ == SweepKind::General) {
            for (const ProfilePiece& p : part.pieces) {
                const auto* a = std::get_if<ArcPiece>(&p);
                if (!a) continue;
                if (a->rc == 0.0) {
                    part.capsules.push_back({a->zc, a->rho, a->z0, a->z1});
                    continue;
                }
                // Torus: the grazing normals are N(psi) = cos(psi) q + sin(psi) e; the grazing
                // point at height zc + rho fd cos(psi) / |f| lies on the piece when that height
                // is in [z0, z1].
                GrazingTorus t;
                t.rc = a->rc, t.zc = a->zc, t.rho = a->rho;
                // cos(psi) = (z - zc) |f| / (rho fd). The lowest grazing point is rho (1 - fd / |f|)
                // above the torus's bottom; decide "the piece reaches it" by comparing products,
                // not through acos of a value one rounding away from -1 (off by 1e-8 rad, more
                // than the whole bottom stretch of a nearly horizontal move).
                const double scale = flen / (a->rho * fd);
                t.cosLo = (a->z0 - a->zc) * flen <= -a->rho * fd ? -1.0 : (a->z0 - a->zc) * scale;
                t.cosHi = (a->z1 - a->zc) * flen >= a->rho * fd ? 1.0 : (a->z1 - a->zc) * scale;
                if (t.cosLo > t.cosHi) continue;
                const double psiA = std::acos(t.cosHi), psiB = std::acos(t.cosLo);
                if (!(psiB > psiA)) continue;
                for (double side : {1.0, -1.0}) {
                    TorusArc& arc = t.arc[t.arcs++];
                    arc.side = side;
                    const double mid = side * 0.5 * (psiA + psiB);
                    arc.cosMid = std::cos(mid), arc.sinMid = std::sin(mid);
                    arc.T = std::tan(0.25 * (psiB - psiA));
                    for (double end : {-1.0, 1.0}) {
                        const double psi = mid + end * 0.5 * (psiB - psiA);
                        const double cp = std::cos(psi), sp = std::sin(psi);
                        const Vec3 pt = torusPoint(t, -fnl * cp / flen, sp, fd * cp / flen);
                        (end < 0 ? arc.endLo : arc.endHi) = pt;
                    }
                }
                // Where the two mirror arcs meet (psi = 0 or pi: the d-n plane), they share the
                // point bit for bit, so that both see the same sign of g there: a line in the
                // plane of symmetry of the move crosses the curve exactly at the junction.
                if (t.cosLo == -1.0) t.arc[1].endLo = t.arc[0].endHi;
                if (t.cosHi == 1.0) t.arc[1].endHi = t.arc[0].endLo;
                part.tori.push_back(t);
            }
            // Rims: the bottom and top faces' edges, and joints where the slope jumps. A rim point
            // grazes where its cone of normals holds one perpendicular to f; its sweep is an
            // elliptic cylinder. Points of a rim that do not graze lie inside the shadow cylinder,
            // so they are harmless extra candidates.
            double nr0, nz0, nr1, nz1;
            if (rBottom > 0.0 && faceMeetsAtAngle(bottom, part.z0)) {
                sideNormal(bottom, part.z0, nr1, nz1);
                part.rims.push_back(rimAt(part.z0, rBottom, 0.0, -1.0, nr1, nz1));
            }
            for (std::size_t i = 0; i + 1 < part.pieces.size(); ++i) {
                const double zj = pieceZ1(part.pieces[i]);
                if (!slopeJumps(part.pieces[i], part.pieces[i + 1], zj)) continue;
                sideNormal(part.pieces[i], zj, nr0, nz0);
                sideNormal(part.pieces[i + 1], zj, nr1, nz1);
                part.rims.push_back(rimAt(zj, pieceRadius(part.pieces[i], zj), nr0, nz0, nr1, nz1));
            }
            if (rTop > 0.0 && faceMeetsAtAngle(top, part.z1)) {
                sideNormal(top, part.z1, nr0, nz0);
                part.rims.push_back(rimAt(part.z1, rTop, nr0, nz0, 0.0, 1.0));
            }
        }

        if (kind_ == SweepKind::Horizontal) {
            for (const ProfilePiece& p : part.pieces)
                if (const auto* a = std::get_if<ArcPiece>(&p)) part.meridianArcs.push_back(*a);
            if (rBottom > 0.0) part.disks.push_back({part.z0, rBottom});
            if (rTop > 0.0) part.disks.push_back({part.z1, rTop});
        }
        parts_.push_back(std::move(part));
    }

    // The oriented boxes: e, and for a moving tool q across the feed and f / |f| along it (the
    // shadow cylinder's cross-section is bounded in e and q); else d and n.
    if (kind_ == SweepKind::General || kind_ == SweepKind::Horizontal)
        boxAxes_ = {Vec3(0.0, 1.0, 0.0), Vec3(-fnl / flen, 0.0, fd / flen), feedLocal_ / flen};
    else
        boxAxes_ = {Vec3(0.0, 1.0, 0.0), Vec3(1.0, 0.0, 0.0), Vec3(0.0, 0.0, 1.0)};
    for (Part& part : parts_) {
        for (int i = 0; i < 3; ++i) {
            const Vec3& a = boxAxes_[i];
            const double xr = std::sqrt(a.x * a.x + a.y * a.y);
            const double along = glm::dot(a, feedLocal_);
            part.box[i] = {-partSupport(part.pieces, -a.z, xr) + std::min(0.0, along),
                           partSupport(part.pieces, a.z, xr) + std::max(0.0, along)};
        }
    }

    // The box: the support function of the sweep in +-x, +-y, +-z is the part's support from the
    // start tip plus max(0, f . direction).
    for (int i = 0; i < 3; ++i) {
        for (double sgn : {1.0, -1.0}) {
            const double xn = sgn * frame_.n[i];
            const double xr = std::sqrt(std::max(0.0, 1.0 - xn * xn));
            double h = -kInf;
            for (const Part& part : parts_) h = std::max(h, partSupport(part.pieces, xn, xr));
            const double along = std::max(0.0, sgn * f[i]);
            if (sgn > 0) bounds_.hi[i] = start[i] + h + along;
            else bounds_.lo[i] = start[i] - h - along;
        }
    }
}

MoveSweep::LocalLine MoveSweep::toLocal(const Line& line) const {
    LocalLine q;
    const Vec3& w = line.dir;
    const Vec3 rel = line.origin - start_;
    // Re-anchor the line at its point nearest the start tip: keeps the local numbers small.
    q.vShift = -glm::dot(rel, w);
    const Vec3 a = rel + q.vShift * w;
    q.o = Vec3(glm::dot(a, frame_.d), glm::dot(a, frame_.e), glm::dot(a, frame_.n));
    q.w = Vec3(glm::dot(w, frame_.d), glm::dot(w, frame_.e), glm::dot(w, frame_.n));
    q.c = glm::cross(q.w, feedLocal_);
    q.c2 = glm::dot(q.c, q.c);
    q.co = glm::dot(q.c, q.o);
    const double par = sweep_tol::kParallelFeed * feedLength_;
    q.parallel = q.c2 <= par * par;
    return q;
}

Interval MoveSweep::boxLocal(const Part& part, const LocalLine& q) const {
    Interval range = Interval::all();
    for (int i = 0; i < 3; ++i) {
        const double oa = glm::dot(q.o, boxAxes_[i]), wa = glm::dot(q.w, boxAxes_[i]);
        const double lo = part.box[i].lo - sweep_tol::kBoxSlack - oa, hi = part.box[i].hi + sweep_tol::kBoxSlack - oa;
        if (wa == 0.0) {
            if (lo > 0.0 || hi < 0.0) return Interval::empty();
            continue;
        }
        const double v0 = lo / wa, v1 = hi / wa;
        range = range.intersect(wa > 0.0 ? Interval{v0, v1} : Interval{v1, v0});
    }
    return range;
}

template <bool kTrace>
Interval MoveSweep::intersectLocal(const Part& part, const LocalLine& q, [[maybe_unused]] EndTrace* trace) const {
    const Vec3& o = q.o;
    const Vec3& w = q.w;
    if (kind_ == SweepKind::Static) {
        if constexpr (kTrace) trace->lo.pose = trace->hi.pose = 0;
        return staticPart(part, o, w);
    }
    if (q.parallel) {
        // A line parallel to the move: the static interval stretched along it by the move.
        const Interval first = staticPart(part, o, w), last = staticPart(part, o - feedLocal_, w);
        if constexpr (kTrace) {
            trace->lo.pose = first.isEmpty() || last.lo < first.lo ? 1 : 0;
            trace->hi.pose = first.isEmpty() || last.hi > first.hi ? 1 : 0;
        }
        return first.hull(last);
    }
    // Early rejection, seen along f: the part lies within rMax of its axis segment, whose ends
    // project at signed distances g / |c| from the projected line (g = c . P - c . o). When both
    // ends are farther than rMax on the same side, the line misses the shadow cylinder.
    const double g0 = q.c.z * part.z0 - q.co, g1 = q.c.z * part.z1 - q.co;
    const double reach = part.rMax + sweep_tol::kBoxSlack;
    if ((g0 > 0.0) == (g1 > 0.0) && std::min(g0 * g0, g1 * g1) > reach * reach * q.c2) return Interval::empty();
    // The oriented box pays only where the exact work is root finding (a flat or ball end mill's
    // closed forms cost little more than the box).
    if (!part.tori.empty() && boxLocal(part, q).isEmpty()) return Interval::empty();

    const double fd = feedLocal_.x, fn = feedLocal_.z;
    Extremes<kTrace> ex;
    if constexpr (kTrace) ex.lo = &trace->lo.sources, ex.hi = &trace->hi.sources;

    if (kind_ == SweepKind::Plunge) {
        // The shadow cylinder is rho = rMax; its point at height z is swept by the tool at u when
        // z - u fn lies where R = rMax.
        double r1, r2;
        const int n = quadraticRoots(w.x * w.x + w.y * w.y, o.x * w.x + o.y * w.y,
                                     o.x * o.x + o.y * o.y - part.rMax * part.rMax, r1, r2);
        for (int i = 0; i < n; ++i) {
            const double v = i ? r2 : r1;
            const double z = o.z + v * w.z;
            const double ua = (z - part.zMax1) / fn, ub = (z - part.zMax0) / fn;
            ex.add(v, std::min(ua, ub), std::max(ua, ub), kNoSource);
        }
    } else {
        // Eq. (31): o + v w = O + t S + u f, solved by triple products with D = w . (S x f).
        for (const GrazingStrip& s : part.strips) {
            const double D = glm::dot(w, s.normal);
            if (std::abs(D) <= s.degenerate) continue;
            const Vec3 r = o - s.origin;
            const double invD = 1.0 / D;
            const double t = -glm::dot(r, q.c) * invD;
            if (t < -sweep_tol::kParam || t > 1.0 + sweep_tol::kParam) continue;
            const double v = -glm::dot(r, s.normal) * invD;
            const double u = glm::dot(r, glm::cross(w, s.span)) * invD;
            ex.add(v, u, Source::of(Source::Strip, std::uint32_t(&s - part.strips.data())));
        }

        if (kind_ == SweepKind::Horizontal) {
            // The profile seen along f: arcs as circles in the (e, n) plane on either side.
            for (const ArcPiece& a : part.meridianArcs) {
                const double zSlack = sweep_tol::kParam * (a.z1 - a.z0);
                for (double side : {1.0, -1.0}) {
                    const double y0 = o.y - side * a.rc, z0 = o.z - a.zc;
                    double r1, r2;
                    const int n = quadraticRoots(w.y * w.y + w.z * w.z, y0 * w.y + z0 * w.z,
                                                 y0 * y0 + z0 * z0 - a.rho * a.rho, r1, r2);
                    for (int i = 0; i < n; ++i) {
                        const double v = i ? r2 : r1;
                        const Vec3 p = o + v * w;
                        if (p.z < a.z0 - zSlack || p.z > a.z1 + zSlack) continue;
                        if (a.rc > 0.0 && side * p.y < a.rc) continue;  // the inner half: not the tool's
                        ex.add(v, p.x / fd, kNoSource);
                    }
                    if (a.rc == 0.0) break;  // a sphere: one circle
                }
            }
            // The flat faces graze: a disk of radius r at height z sweeps a stadium in its plane.
            for (const Circle& disk : part.disks) {
                if (std::abs(w.z) <= tol::kParallel) {
                    // A line lying in the face's plane (method.md section 5: closed convention,
                    // the face's points are removed) crosses the stadium's sides y = +-r.
                    if (std::abs(o.z - disk.z) > tol::kLength || w.y == 0.0) continue;
                    for (double side : {1.0, -1.0}) {
                        const double v = (side * disk.r - o.y) / w.y;
                        ex.add(v, (o.x + v * w.x) / fd, kNoSource);
                    }
                    continue;
                }
                const double v = (disk.z - o.z) / w.z;
                const Vec3 p = o + v * w;
                const double s2 = disk.r * disk.r - p.y * p.y;
                if (s2 < 0.0) continue;
                const double s = std::sqrt(s2);
                ex.add(v, (p.x - s) / fd, (p.x + s) / fd, kNoSource);
            }
        } else {
            // Sphere: the grazing great circle perpendicular to f sweeps a cylinder of radius rho
            // about the centre's path (with the start and end spheres: a capsule).
            for (const GrazingCapsule& cap : part.capsules) {
                const Vec3 r(o.x, o.y, o.z - cap.zc);
                const double rf = glm::dot(r, feedLocal_), wf = glm::dot(w, feedLocal_);
                double r1, r2;
                const int n = quadraticRoots(q.c2 * invF2_, glm::dot(r, w) - rf * wf * invF2_,
                                             glm::dot(r, r) - rf * rf * invF2_ - cap.rho * cap.rho, r1, r2);
                const double zSlack = sweep_tol::kParam * (cap.z1 - cap.z0);
                for (int i = 0; i < n; ++i) {
                    const double v = i ? r2 : r1;
                    const double u = (rf + v * wf) * invF2_;
                    const double z = o.z + v * w.z - u * fn;  // height of the grazing point
                    if (z < cap.z0 - zSlack || z > cap.z1 + zSlack) continue;
                    ex.add(v, u, Source::of(Source::Capsule, std::uint32_t(&cap - part.capsules.data())));
                }
            }

            // Torus: Eq. (36) and Algorithm 1 (see torusCrossings).
            if (!part.tori.empty()) {
                const TorusLine tl{o, w, q.c, q.c2, q.co, feedLocal_};
                for (const GrazingTorus& tor : part.tori)
                    torusCrossings(tor, std::uint32_t(&tor - part.tori.data()), tl, ex);
            }

            // Rims: the sweep of a rim circle (radius r at height zr) is an elliptic cylinder.
            // Seen along f it is the ellipse with semi-axes r along e and r kappa along q,
            // kappa = |fn| / |f|, centred at q = fd zr / |f|. The projected line o + v w crosses it
            // where, with dq = o.q - fd zr / |f| (the rim's qc) and a = kappa^2 w.e^2 + (w.q)^2,
            //   v = (-(kappa^2 o.e w.e + dq w.q) +- kappa sqrt(r^2 a - (o.e w.q - w.e dq)^2)) / a,
            // a form in which nothing cancels when the move is nearly horizontal (kappa -> 0).
            // The feed parameter follows from the axial row: u = (o.z + v w.z - zr) / fn.
            const double kappa2 = kappa_ * kappa_;
            const double oq = glm::dot(o, qDir_), wq = glm::dot(w, qDir_);
            const double a = kappa2 * w.y * w.y + wq * wq;
            const double invA = 1.0 / a;
            for (const Circle& rim : part.rims) {
                const double dq = oq - rim.qc;
                const double cross = o.y * wq - w.y * dq;
                const double disc = rim.r * rim.r * a - cross * cross;
                if (disc < 0.0 || a == 0.0) continue;
                const double b = kappa2 * o.y * w.y + dq * wq;
                const double c = kappa2 * (o.y * o.y - rim.r * rim.r) + dq * dq;
                const double qq = -(b + std::copysign(kappa_ * std::sqrt(disc), b));
                const double roots[2] = {qq * invA, qq != 0.0 ? c / qq : qq * invA};
                const Source src = Source::of(Source::Rim, std::uint32_t(&rim - part.rims.data()));
                for (double v : roots) ex.add(v, (o.z + v * w.z - rim.z) * invFn_, src);
            }
        }
    }

    if (ex.empty()) return Interval::empty();  // the line misses the shadow cylinder
    // Each end: the boundary crossing when a tool pose in the move puts it there, otherwise the
    // static tool at the nearer end of the move.
    Interval statics[2];
    bool have[2] = {false, false};
    auto staticAt = [&](int end) -> const Interval& {
        if (!have[end]) {
            statics[end] = staticPart(part, end ? o - feedLocal_ : o, w);
            have[end] = true;
        }
        return statics[end];
    };
    Interval out;
    if (ex.hiU1 >= 0.0 && ex.hiU0 <= 1.0) {
        out.hi = ex.vHi;
        if constexpr (kTrace) trace->hi.pose = -1, trace->hi.u0 = ex.hiU0, trace->hi.u1 = ex.hiU1;
    } else {
        const int pose = ex.hiU0 > 1.0 ? 1 : 0;
        const Interval& s = staticAt(pose);
        if (s.isEmpty()) return s;
        out.hi = s.hi;
        if constexpr (kTrace) trace->hi.pose = pose;
    }
    if (ex.loU1 >= 0.0 && ex.loU0 <= 1.0) {
        out.lo = ex.vLo;
        if constexpr (kTrace) trace->lo.pose = -1, trace->lo.u0 = ex.loU0, trace->lo.u1 = ex.loU1;
    } else {
        const int pose = ex.loU0 > 1.0 ? 1 : 0;
        const Interval& s = staticAt(pose);
        if (s.isEmpty()) return s;
        out.lo = s.lo;
        if constexpr (kTrace) trace->lo.pose = pose;
    }
    return out;
}

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

Interval MoveSweep::bound(const Line& line) const { return bound(toLocal(line)); }

Interval MoveSweep::bound(const LocalLine& q) const {
    Interval hull;
    for (const Part& part : parts_) {
        Interval range = boxLocal(part, q);
        if (range.isEmpty()) continue;
        if (q.w.x == 0.0 && q.w.y == 0.0 && kind_ != SweepKind::Static) {
            // A line along the axis: at distance r from the axis of the tool at u, it is inside
            // that tool only where R(z) >= r. r is at least the distance rMin from the swept axis,
            // and {z : R(z) >= rMin} is one interval [zLo, zHi] (R is concave on a part), so the
            // line is inside the sweep only at heights [zLo + min(0, fn), zHi + max(0, fn)].
            const double fd = feedLocal_.x, fn = feedLocal_.z;
            const double x = std::clamp(q.o.x, std::min(0.0, fd), std::max(0.0, fd));
            const double dx = q.o.x - x;  // mm-sized: no need for hypot's overflow care
            const double rMin = std::sqrt(dx * dx + q.o.y * q.o.y) - sweep_tol::kBoxSlack;
            const Interval z = part.widerThan(rMin);
            if (z.isEmpty()) continue;
            const double zLo = z.lo + std::min(0.0, fn) - sweep_tol::kBoxSlack;
            const double zHi = z.hi + std::max(0.0, fn) + sweep_tol::kBoxSlack;
            const double v0 = (zLo - q.o.z) / q.w.z, v1 = (zHi - q.o.z) / q.w.z;
            range = range.intersect(q.w.z > 0.0 ? Interval{v0, v1} : Interval{v1, v0});
            if (range.isEmpty()) continue;
        }
        hull = hull.hull(range);
    }
    if (hull.isEmpty()) return hull;
    return {hull.lo + q.vShift, hull.hi + q.vShift};
}

std::size_t MoveSweep::intersectParts(const Line& line, Interval* out) const {
    return intersectParts(toLocal(line), out);
}

std::size_t MoveSweep::intersectParts(const LocalLine& q, Interval* out) const {
    for (std::size_t i = 0; i < parts_.size(); ++i) {
        const Interval iv = intersectLocal<false>(parts_[i], q, nullptr);
        out[i] = iv.isEmpty() ? Interval::empty() : Interval{iv.lo + q.vShift, iv.hi + q.vShift};
    }
    return parts_.size();
}

std::size_t MoveSweep::intersectParts(const Line& line, LineHit* out) const {
    return intersectParts(line, out, [](std::size_t, const Interval&) { return kEndLo | kEndHi; });
}

std::size_t MoveSweep::intersectParts(const Line& line, LineHit* out, const EndFilter& wanted) const {
    return intersectParts(toLocal(line), out, wanted);
}

std::size_t MoveSweep::intersectParts(const LocalLine& q, LineHit* out, const EndFilter& wanted) const {
    for (std::size_t i = 0; i < parts_.size(); ++i) {
        EndTrace trace;
        const Interval iv = intersectLocal<true>(parts_[i], q, &trace);
        LineHit& hit = out[i];
        hit = LineHit{};
        if (iv.isEmpty()) continue;
        hit.range = {iv.lo + q.vShift, iv.hi + q.vShift};
        const unsigned ends = wanted(i, hit.range);
        if (ends) hermite(i, q, iv, trace, ends, hit);
    }
    return parts_.size();
}

Interval MoveSweep::intersect(const Line& line) const {
    if (parts_.size() == 1) {
        const LocalLine q = toLocal(line);
        const Interval iv = intersectLocal<false>(parts_[0], q, nullptr);
        return iv.isEmpty() ? Interval::empty() : Interval{iv.lo + q.vShift, iv.hi + q.vShift};
    }
    Interval parts[kMaxParts];
    const std::size_t n = intersectParts(line, parts);
    Interval hull;
    for (std::size_t i = 0; i < n; ++i) hull = hull.hull(parts[i]);
    return hull;
}

std::vector<Interval> MoveSweep::intersectAll(const Line& line) const {
    Interval parts[kMaxParts];
    const std::size_t n = intersectParts(line, parts);
    std::vector<Interval> ivs;
    for (std::size_t i = 0; i < n; ++i)
        if (!parts[i].isEmpty()) ivs.push_back(parts[i]);
    std::sort(ivs.begin(), ivs.end(), [](const Interval& a, const Interval& b) { return a.lo < b.lo; });
    std::vector<Interval> merged;
    for (const Interval& iv : ivs) {
        if (!merged.empty() && iv.lo <= merged.back().hi) merged.back().hi = std::max(merged.back().hi, iv.hi);
        else merged.push_back(iv);
    }
    return merged;
}

}  // namespace dexelmill
