#include "dexelmill/tool/tool.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include <boost/math/tools/roots.hpp>

#include "dexelmill/decimal.h"
#include "dexelmill/error.h"
#include "dexelmill/geometry/roots.h"
#include "dexelmill/geometry/tolerance.h"

namespace dexelmill {

namespace {

std::string num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

/// Moves a height within `tol::kProfileJoint` of `target` onto it.
double snap(double z, double target) {
    return std::abs(z - target) <= tol::kProfileJoint ? target : z;
}

/// The largest R of a piece over heights [z0, z1] within it.
double maxRadiusOver(const ProfilePiece& p, double z0, double z1) {
    const double ends = std::max(pieceRadius(p, z0), pieceRadius(p, z1));
    if (const auto* a = std::get_if<ArcPiece>(&p)) {
        if (z0 <= a->zc && a->zc <= z1) return a->rc + a->rho;
    }
    return ends;
}

/// rho(t) - R(z(t)) along the line for a torus piece: negative inside its slab solid.
double torusGap(const ArcPiece& a, const LocalLine& l, double t) {
    const double r2 = std::max(0.0, (l.A * t + 2.0 * l.B) * t + l.C);
    const double dz = l.z0 + l.zv * t - a.zc;
    return std::sqrt(r2) - a.rc - std::sqrt(std::max(0.0, a.rho * a.rho - dz * dz));
}

/// q(t) = max(rho - rc, 0)^2 + dz^2 - rho_a^2 along the line, its slope and its curvature, for
/// torusInterval (which says why): q' = 2 ((rho - rc)+ (A t + B) / rho + dz zv), and
/// q'' = 2 (zv^2 + (A t + B)^2 / rho^2 + (rho - rc) (A C - B^2) / rho^3) where rho > rc, else 2 zv^2,
/// only with kCurve (the root finding needs none).
struct TorusQ {
    double value = 0.0, slope = 0.0, curve = 0.0;
};
template <bool kCurve>
TorusQ torusQ(const ArcPiece& a, const LocalLine& l, double t) {
    const double r2 = std::max(0.0, (l.A * t + 2.0 * l.B) * t + l.C), r = std::sqrt(r2);
    const double dz = l.z0 + l.zv * t - a.zc, out = std::max(r - a.rc, 0.0);
    const double radial = r > 0.0 ? (l.A * t + l.B) / r : 0.0;
    TorusQ q;
    q.value = out * out + dz * dz - a.rho * a.rho;
    q.slope = 2.0 * (out * radial + dz * l.zv);
    if constexpr (kCurve) {
        q.curve = 2.0 * (l.zv * l.zv + (out > 0.0 ? radial * radial + out * (l.A * l.C - l.B * l.B) / (r2 * r) : 0.0));
    }
    return q;
}

/// detail::torusClosedForm; where it returns false, `range` (the slab within the outer cylinder) and
/// the gaps at its ends are left for the root finding.
bool torusClosedFormOrStart(const ArcPiece& a, const LocalLine& l, const Interval& slab, Interval& out,
                            Interval& range, double& gLo, double& gHi) {
    if (l.A <= tol::kParallel * tol::kParallel * l.zv * l.zv && l.zv != 0.0) {
        // A line parallel to the axis (A = 0) at distance sqrt(C): inside where the profile
        // circle is at least that far out, |z - zc| <= sqrt(rho^2 - (sqrt(C) - rc)^2), or over the
        // whole slab when it runs inside the core (sqrt(C) <= rc). Closed form: the convex search
        // below would look for a minimum of a function that is flat in the radial term.
        const double outside = std::sqrt(l.C) - a.rc;
        if (outside <= 0.0) {
            out = slab;
        } else if (outside > a.rho) {
            out = Interval::empty();
        } else {
            const double half = std::sqrt(a.rho * a.rho - outside * outside);
            out = slab.intersect(detail::slabRange(l, a.zc - half, a.zc + half));
        }
        return true;
    }
    range = slab.intersect(detail::cylinderRange(l, a.rc + a.rho));
    if (range.isEmpty()) {
        out = range;
        return true;
    }
    if (l.zv == 0.0) {
        // Constant height: a disk of radius R(z0).
        const double dz = l.z0 - a.zc;
        const double r = a.rc + std::sqrt(std::max(0.0, a.rho * a.rho - dz * dz));
        out = detail::cylinderRange(l, r).intersect(range);
        return true;
    }
    gLo = torusGap(a, l, range.lo);
    gHi = torusGap(a, l, range.hi);
    if (gLo <= 0.0 && gHi <= 0.0) {  // convex: the whole range is inside
        out = range;
        return true;
    }
    return false;
}

}  // namespace

bool detail::torusClosedForm(const ArcPiece& a, const LocalLine& l, const Interval& slab, Interval& out) {
    Interval range;
    double gLo = 0.0, gHi = 0.0;
    return torusClosedFormOrStart(a, l, slab, out, range, gLo, gHi);
}

namespace {

// Torus slab: g(t) = rho(t) - R(z(t)) is convex on the slab (a norm of an affine map minus a
// concave function of an affine map), so { g <= 0 } is one interval. Any point t with g(t) <= 0
// splits it: its lower end lies in [range.lo, t] and its upper in [t, range.hi], each the one
// root of g there, which Newton's method (on q below) or TOMS 748 finds. (A point with g = 0
// splits it only if it is the minimum: the probes below need g < 0.) Two points come first, where
// g tends to be least: where the line comes nearest the axis (rho least) and where it crosses the
// profile circle's height (R greatest). Where neither lies inside, the least of q (below), which
// has g's sign on the slab, is found, and a positive one means the line misses: q is strictly
// convex there (q'' >= 2 zv^2, and zv = 0 is decided in closed form), so its least is where its
// increasing slope q' changes sign, which newtonBracket finds with q'', stopping at the first
// point where q < 0. (Boost's Brent minimisation of g took 12.7 evaluations, this 4.5, on
// BM_TurningQuery's bull-nose x lines, 4.3 times a line: the bull nose's rows 0.93-0.98.) The
// ends do not depend on which inner point splits them, beyond the root finder's tolerance. A
// local line's parameter is measured from where it passes nearest the tip, so the brackets are
// tool-sized and close well within newtonBracket's steps.
//
// Each end is found to within `tolerance` along the line, and taken as the midpoint of the final
// bracket, or with `outer` as its end outside the interval: then the result holds the exact
// interval. (Where q's least is positive by less than its rounding, about 1e-16 of the slab's
// size squared, the line grazes the torus and an empty interval is returned either way.)
//
// `near`, where not empty, is an interval whose ends are likely about `reach` inside the torus's
// ends (the ungrown tool's, for a torus grown by reach): each end of near that lies inside splits
// the interval, and from it steps of 2 reach, 8 reach, ... outwards find a point outside, so that
// the root finding starts on a bracket about as wide as the step (each point inside found on the
// way replaces the inner end). Any `near` gives the same result; a good one only saves work.
Interval torusInterval(const ArcPiece& a, const LocalLine& l, const Interval& slab, double tolerance, bool outer,
                       const Interval& near, double reach) {
    Interval decided, range;
    double gLo = 0.0, gHi = 0.0;
    if (torusClosedFormOrStart(a, l, slab, decided, range, gLo, gHi)) return decided;
    auto g = [&](double t) { return torusGap(a, l, t); };
    double tMin = 0.0, gMin = 0.0;
    // torusClosedFormOrStart has decided lines along the axis (l.A = 0) and at one height (zv = 0).
    const auto inRange = [&](double t) { return std::clamp(t, range.lo, range.hi); };
    const double nearAxis = inRange(-l.B / l.A), atCircle = inRange((a.zc - l.z0) / l.zv);
    // The ends of `near` inside, with g there (NaN where not tried or not inside).
    const double kUntried = std::numeric_limits<double>::quiet_NaN();
    double nearLo = kUntried, gNearLo = kUntried, nearHi = kUntried, gNearHi = kUntried;
    if (!near.isEmpty() && reach > 0.0) {
        if (const double t = inRange(near.lo), gt = g(t); gt < 0.0) nearLo = t, gNearLo = gt;
        if (const double t = inRange(near.hi), gt = g(t); gt < 0.0) nearHi = t, gNearHi = gt;
    }
    if (gNearLo < 0.0) {
        tMin = nearLo, gMin = gNearLo;
    } else if (gNearHi < 0.0) {
        tMin = nearHi, gMin = gNearHi;
    } else if (const double gAxis = g(nearAxis); gAxis < 0.0) {
        tMin = nearAxis, gMin = gAxis;
    } else if (const double gCircle = g(atCircle); gCircle < 0.0) {
        tMin = atCircle, gMin = gCircle;
    } else {
        // q' and q'' at t; the search stops at the first point where q < 0 (an inner point).
        const auto slopes = [&](double t, double& slope, double& curve) {
            const TorusQ at = torusQ<true>(a, l, t);
            slope = at.slope, curve = at.curve;
            return at.value >= 0.0;
        };
        double sLo = 0.0, sHi = 0.0, curve = 0.0;
        slopes(range.lo, sLo, curve);
        slopes(range.hi, sHi, curve);
        if (sLo >= 0.0) {
            tMin = range.lo;
        } else if (sHi <= 0.0) {
            tMin = range.hi;
        } else {
            // To the root tolerance whatever the ends': an outer interval's slack, a bracket that
            // wide, could end the search before it met a point inside and call a hit a miss.
            const auto least = newtonBracket(slopes, range.lo, range.hi, sLo, sHi, tol::kRoot);
            tMin = 0.5 * (least.first + least.second);
        }
        gMin = g(tMin);
    }
    if (gMin > 0.0) return Interval::empty();
    // The root finding works on q(t) = max(rho - rc, 0)^2 + dz^2 - rho_a^2, which inside the slab
    // is zero where g is and has its sign (where rho < rc, q = dz^2 - rho_a^2 < 0 and g < 0), but
    // has a finite slope where the line leaves through the slab's bottom or top face's rim, where
    // g's square root has an infinite one, and needs one square root, not two. q is convex too
    // ((rho - rc)+ squared and dz squared are), and smooth, with
    // q' = 2 ((rho - rc)+ (A t + B) / rho + dz zv): Newton's method (newtonBracket) evaluates q
    // about as often as TOMS 748 did (6.6 against 6.4 times an end, on random lines near a bull
    // nose's torus), for a fraction of its interpolation's work: BM_TurningQuery's bull nose
    // 0.84-0.87 of the time. A bracket whose end q does not sign as g does (rounding, or an end
    // on a face where q = 0) keeps g and TOMS 748, and so does a call with a hint (its brackets are
    // narrow, and q's one evaluation more would not pay).
    const auto q = [&](double t) { return torusQ<false>(a, l, t).value; };
    const double qMin = near.isEmpty() ? q(tMin) : kUntried;
    const auto stop = [tolerance](double x, double y) { return std::abs(y - x) <= tolerance; };
    // The root between x0 (outside, g > 0) and x1 (inside, g < 0), either way round; `in`, where
    // g < 0 there, is a point inside nearer the root.
    const auto root = [&](double x0, double x1, double gOut, double in, double gIn) {
        boost::uintmax_t iters = 100;
        if (gIn < 0.0) {
            const double away = x0 < in ? -1.0 : 1.0;
            for (double d = 2.0 * reach; away * (x0 - in) > d; d *= 4.0) {
                const double t = in + away * d, gt = g(t);
                if (gt > 0.0) {
                    x0 = t, gOut = gt;
                    break;
                }
                in = t, gIn = gt;
            }
            const auto [lo, hi] = std::minmax(x0, in);
            return boost::math::tools::toms748_solve(g, lo, hi, x0 < in ? gOut : gIn, x0 < in ? gIn : gOut, stop,
                                                     iters);
        }
        const double qOut = q(x0);
        const bool smooth = qOut > 0.0 && qMin < 0.0;
        const auto [lo, hi] = std::minmax(x0, x1);
        if (smooth) {
            const auto qSlope = [&](double t, double& value, double& slope) {
                const TorusQ at = torusQ<false>(a, l, t);
                value = at.value, slope = at.slope;
                return true;
            };
            return newtonBracket(qSlope, x0, x1, qOut, qMin, tolerance);
        }
        const double gLo = x0 < x1 ? gOut : gMin, gHi = x0 < x1 ? gMin : gOut;
        return boost::math::tools::toms748_solve(g, lo, hi, gLo, gHi, stop, iters);
    };
    Interval out{range.lo, range.hi};
    if (gLo > 0.0) {
        if (gMin == 0.0) {
            out.lo = tMin;
        } else {
            const auto r = root(range.lo, tMin, gLo, nearLo, gNearLo);
            out.lo = outer ? r.first : 0.5 * (r.first + r.second);
        }
    }
    if (gHi > 0.0) {
        if (gMin == 0.0) {
            out.hi = tMin;
        } else {
            const auto r = root(range.hi, tMin, gHi, nearHi, gNearHi);
            out.hi = outer ? r.second : 0.5 * (r.first + r.second);
        }
    }
    return out;
}

}  // namespace

Interval detail::intersectTorus(const ArcPiece& a, const LocalLine& l, const Interval& slab) {
    return torusInterval(a, l, slab, tol::kRoot, false, Interval::empty(), 0.0);
}

Interval detail::outerTorusInterval(const ArcPiece& a, const LocalLine& l, const Interval& slab, double slack,
                                    const Interval& near, double reach) {
    return torusInterval(a, l, slab, std::max(slack, tol::kRoot), true, near, reach);
}

LocalLine LocalLine::make(const ToolPose& pose, const Line& line) {
    const Vec3& w = line.dir;
    const Vec3& n = pose.axis;
    LocalLine l;
    const Vec3 a0 = line.origin - pose.tip;
    l.vShift = -glm::dot(a0, w) / glm::dot(w, w);
    const Vec3 a = a0 + l.vShift * w;  // the line point nearest the tip
    l.z0 = glm::dot(a, n);
    l.zv = glm::dot(w, n);
    const Vec3 aPerp = a - l.z0 * n;
    const Vec3 wPerp = w - l.zv * n;
    l.A = glm::dot(wPerp, wPerp);
    l.B = glm::dot(aPerp, wPerp);
    l.C = glm::dot(aPerp, aPerp);
    return l;
}

Tool::Tool(std::string description, std::vector<ProfilePiece> pieces, double cuttingLength)
    : description_(std::move(description)), pieces_(std::move(pieces)) {
    const std::string who = "tool '" + description_ + "': ";
    if (pieces_.empty()) throw Error(who + "the profile has no pieces");
    double z = std::visit([](auto& p) { return p.z0; }, pieces_.front());
    if (!(z >= -tol::kProfileJoint))
        throw Error(who + "the profile starts below the tip, at z = " + num(z));
    z = std::max(z, 0.0);
    bottom_ = z;
    for (std::size_t i = 0; i < pieces_.size(); ++i) {
        const std::string at = who + "piece " + std::to_string(i + 1) + ": ";
        std::visit(
            [&](auto& p) {
                p.z0 = snap(p.z0, z);
                if (p.z0 != z)
                    throw Error(at + "starts at z = " + num(p.z0) +
                                " but the previous piece ends at z = " + num(z));
                if (!(p.z1 > p.z0 + tol::kLength) || !std::isfinite(p.z1))
                    throw Error(at + "has no height (z0 = " + num(p.z0) + ", z1 = " + num(p.z1) +
                                ")");
                z = p.z1;
            },
            pieces_[i]);
        if (const auto* c = std::get_if<ConePiece>(&pieces_[i])) {
            if (!(c->r0 >= 0.0) || !(c->r1 >= 0.0) || !std::isfinite(c->r0) ||
                !std::isfinite(c->r1))
                throw Error(at + "negative radius (r0 = " + num(c->r0) + ", r1 = " + num(c->r1) +
                            ")");
        } else {
            auto& a = std::get<ArcPiece>(pieces_[i]);
            if (!(a.rho > 0.0) || !std::isfinite(a.rho))
                throw Error(at + "arc radius must be positive, got " + num(a.rho));
            if (!(a.rc >= 0.0))
                throw Error(at + "arc centre is left of the axis (rc = " + num(a.rc) + ")");
            a.z0 = std::max(a.z0, snap(a.z0, a.zc - a.rho));
            a.z1 = std::min(a.z1, snap(a.z1, a.zc + a.rho));
            if (a.z0 < a.zc - a.rho || a.z1 > a.zc + a.rho)
                throw Error(at + "spans z = " + num(a.z0) + " .. " + num(a.z1) +
                            ", outside its circle");
        }
    }
    totalLength_ = z;
    if (!(cuttingLength > bottom_) || cuttingLength > totalLength_ + tol::kProfileJoint)
        throw Error(who + "cutting length " + num(cuttingLength) + " must lie in (" + num(bottom_) +
                    ", " + num(totalLength_) + "]");
    cuttingLength_ = std::min(cuttingLength, totalLength_);

    // Convex parts: split where R jumps (a step face) or where the slope increases (a concave
    // joint: R is then not concave across it).
    ConvexPart part{0, 1, bottom_, pieceZ1(pieces_.front())};
    for (std::size_t i = 0; i + 1 < pieces_.size(); ++i) {
        const double zj = pieceZ1(pieces_[i]);
        const double rLeft = pieceRadius(pieces_[i], zj), rRight = pieceRadius(pieces_[i + 1], zj);
        const double sLeft = pieceSlope(pieces_[i], zj), sRight = pieceSlope(pieces_[i + 1], zj);
        const bool step = std::abs(rLeft - rRight) > tol::kProfileJoint;
        const bool concaveJoint = sRight > sLeft + tol::kSlope * std::max(1.0, std::abs(sLeft));
        if (step || concaveJoint) {
            parts_.push_back(part);
            part = ConvexPart{i + 1, i + 1, zj, zj};
        }
        part.last = i + 2;
        part.z1 = pieceZ1(pieces_[i + 1]);
    }
    parts_.push_back(part);

    for (const ProfilePiece& p : pieces_) {
        maxRadius_ = std::max(maxRadius_, maxRadiusOver(p, pieceZ0(p), pieceZ1(p)));
        if (pieceZ0(p) < cuttingLength_)
            cuttingRadius_ = std::max(
                cuttingRadius_, maxRadiusOver(p, pieceZ0(p), std::min(pieceZ1(p), cuttingLength_)));
    }
    if (!(maxRadius_ > 0.0)) throw Error(who + "the profile has no positive radius");
    // The builders check the sizes they are given; this catches those they derive (a taper's top).
    const std::pair<const char*, double> sizes[] = {{"largest diameter", 2.0 * maxRadius_}, {"length", totalLength_}};
    for (const auto& [what, size] : sizes) {
        if (size <= kMaxToolSizeMm) continue;
        const auto [value, cap] = decimalsApart(size, kMaxToolSizeMm);
        throw Error(who + "its " + what + ", " + value + " mm, is beyond the " + cap + " mm a tool may measure");
    }
}

double Tool::radiusAt(double z) const {
    if (z < bottom_ || z > totalLength_) return -1.0;
    double r = -1.0;
    for (const ProfilePiece& p : pieces_) {
        if (z >= pieceZ0(p) && z <= pieceZ1(p)) r = std::max(r, pieceRadius(p, z));
    }
    return r;
}

bool Tool::containsLocal(double rho, double z) const {
    const double r = radiusAt(z);
    return r >= 0.0 && rho <= r;
}

bool Tool::contains(const ToolPose& pose, const Vec3& p) const {
    const Vec3 d = p - pose.tip;
    const double z = glm::dot(d, pose.axis);
    return containsLocal(glm::length(d - z * pose.axis), z);
}

Interval Tool::intersectPart(const ConvexPart& part, const LocalLine& line) const {
    Interval hull;
    for (std::size_t i = part.first; i < part.last; ++i)
        hull = hull.hull(intersectPiece(pieces_[i], line));
    if (hull.isEmpty()) return hull;
    return {hull.lo + line.vShift, hull.hi + line.vShift};
}

std::vector<Interval> Tool::intersect(const ToolPose& pose, const Line& line) const {
    const LocalLine local = LocalLine::make(pose, line);
    std::vector<Interval> out;
    for (const ConvexPart& part : parts_) {
        const Interval iv = intersectPart(part, local);
        if (!iv.isEmpty()) out.push_back(iv);
    }
    std::sort(out.begin(), out.end(),
              [](const Interval& a, const Interval& b) { return a.lo < b.lo; });
    std::vector<Interval> merged;
    for (const Interval& iv : out) {
        if (!merged.empty() && iv.lo <= merged.back().hi) {
            merged.back().hi = std::max(merged.back().hi, iv.hi);
        } else {
            merged.push_back(iv);
        }
    }
    return merged;
}

Tool Tool::region(double z0, double z1) const {
    z0 = std::max(z0, bottom_);
    z1 = std::min(z1, totalLength_);
    if (!(z1 > z0 + tol::kLength))
        throw Error("tool '" + description_ + "': region " + num(z0) + " .. " + num(z1) +
                    " has no height");
    Tool out(description_ + " [z " + num(z0) + ".." + num(z1) + "]", clipChain(pieces_, 0, pieces_.size(), z0, z1), z1);
    if (holderBottom_ < z1 - tol::kLength) out.holderBottom_ = holderBottom_;
    return out;
}

}  // namespace dexelmill
