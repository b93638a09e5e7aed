#include "dexelmill/sweep/turning.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"
#include "dexelmill/tool/offset.h"

namespace dexelmill {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// The deepest level of the search: a node of width 2^-kMaxLevel. Reached only when
/// speed / 2^(kMaxLevel + 1) is still above epsilon, i.e. a tool point travelling 1e14 epsilon.
constexpr int kMaxLevel = 60;

/// Slack (mm) on the box of the poses: keeps rounding of the box from cutting off a contact.
constexpr double kBoxSlack = 1e-9;

/// An output end within this many tolerances of two faces of its pose's tool whose normals differ
/// takes its Hermite data from the rim where they meet (TurningSweep::endNormal).
constexpr double kRimReach = 4.0;

/// Two faces at a rim whose normals differ by less than this angle (rad) meet smoothly: about the
/// resolution of the normals the stock keeps (PackedNormal::kMaxAngleError).
constexpr double kRimAngle = 1e-4;

/// The largest g(c) = length max(c, 0) + radius sqrt(1 - c^2) over c in [lo, hi] (turning.h).
double reachAlong(double lo, double hi, double length, double radius) {
    const double peak = length / std::hypot(length, radius);
    double best = -std::numeric_limits<double>::infinity();
    for (const double c : {lo, hi, 0.0, peak}) {
        if (c < lo || c > hi) continue;
        best = std::max(best, length * std::max(c, 0.0) + radius * std::sqrt(std::max(0.0, 1.0 - c * c)));
    }
    return best;
}

/// The great circle a move's axis turns on: a(t) = a0 cos t + b sin t, t in [0, theta], with b the
/// unit tangent at a0 towards the end axis (zero, and theta 0, when the axis does not turn).
struct GreatCircle {
    Vec3 a0{0.0, 0.0, 1.0}, b{0.0};
    double theta = 0.0;
};

GreatCircle greatCircle(const Move& m) {
    GreatCircle c;
    c.a0 = m.turns() ? *m.startAxis : m.axis;
    const Vec3 across = m.axis - glm::dot(m.axis, c.a0) * c.a0;
    const double acrossLength = glm::length(across);
    if (acrossLength > 0.0) {
        c.b = across / acrossLength;
        c.theta = turnAngle(m);
    }
    return c;
}

/// The parameter range of `line` inside `box`; empty when it misses.
Interval lineInBox(const Line& line, const Box& box) {
    Interval range = Interval::all();
    for (int i = 0; i < 3; ++i) {
        const double o = line.origin[i], d = line.dir[i];
        if (d == 0.0) {
            if (o < box.lo[i] || o > box.hi[i]) return Interval::empty();
            continue;
        }
        double t0 = (box.lo[i] - o) / d, t1 = (box.hi[i] - o) / d;
        if (t0 > t1) std::swap(t0, t1);
        range = range.intersect({t0, t1});
    }
    return range;
}

/// One output interval with where each end came from: the pose u and the part whose interval
/// made it.
struct Piece {
    Interval range;
    double uLo = 0.0, uHi = 0.0;
    std::size_t partLo = 0, partHi = 0;
};

/// The union of static-pose intervals found so far: sorted, disjoint.
class Union {
  public:
    void add(const Interval& iv, double u, std::size_t part) {
        Piece p{iv, u, u, part, part};
        auto it = std::lower_bound(pieces_.begin(), pieces_.end(), iv.lo,
                                   [](const Piece& q, double lo) { return q.range.hi < lo; });
        // Merge every piece that overlaps or touches the new one.
        auto last = it;
        while (last != pieces_.end() && last->range.lo <= iv.hi) {
            if (last->range.lo < p.range.lo) p.range.lo = last->range.lo, p.uLo = last->uLo, p.partLo = last->partLo;
            if (last->range.hi > p.range.hi) p.range.hi = last->range.hi, p.uHi = last->uHi, p.partHi = last->partHi;
            ++last;
        }
        it = pieces_.erase(it, last);
        pieces_.insert(it, p);
    }
    /// Whether [lo, hi] lies inside one piece.
    bool holds(double lo, double hi) const {
        auto it = std::lower_bound(pieces_.begin(), pieces_.end(), lo,
                                   [](const Piece& q, double v) { return q.range.hi < v; });
        return it != pieces_.end() && it->range.lo <= lo && hi <= it->range.hi;
    }
    const std::vector<Piece>& pieces() const { return pieces_; }

  private:
    std::vector<Piece> pieces_;
};

}  // namespace

double turnAngle(const Move& m) {
    if (!m.turns()) return 0.0;
    return std::atan2(glm::length(glm::cross(*m.startAxis, m.axis)), glm::dot(*m.startAxis, m.axis));
}

namespace {

/// The box of the tool (within `radius` of its axis, heights [0, length] above the tip) at one pose.
Box poseBox(const ToolPose& p, double length, double radius) {
    Box box;
    box.expand(p.tip);
    for (int i = 0; i < 3; ++i) {
        box.lo[i] -= reachAlong(-p.axis[i], -p.axis[i], length, radius);
        box.hi[i] += reachAlong(p.axis[i], p.axis[i], length, radius);
    }
    return box;
}

/// Most poses the box of a machine's rotary move is sampled at.
constexpr int kMaxBoxSamples = 4096;

}  // namespace

Box turningMoveBox(const Move& m, double length, double radius) {
    if (m.rotary) {
        // Samples at u_k = (k + 1/2) / N: every u lies within 1 / (2N) of one, so every pose lies
        // within V / (2N) of a sampled pose (V the law's speed bound), and the union of the sampled
        // poses' boxes padded by that holds them all. N makes the padding at most a tenth of the
        // radius (or a hundredth of a millimetre), up to kMaxBoxSamples.
        const MotionLaw law(m);
        const double speed = law.speedBound(std::hypot(length, radius));
        const double target = std::max(0.1 * radius, 0.01);
        const int n = int(std::clamp(std::ceil(speed / (2.0 * target)), 1.0, double(kMaxBoxSamples)));
        Box box;
        for (int k = 0; k < n; ++k) {
            const Box b = poseBox(law.pose((k + 0.5) / n), length, radius);
            box.expand(b.lo);
            box.expand(b.hi);
        }
        return box.padded(speed / (2.0 * n));
    }
    const GreatCircle turn = greatCircle(m);
    const Vec3 &a0 = turn.a0, &b = turn.b;
    const double theta = turn.theta;
    if (glm::dot(a0, m.axis) < 0.0 && glm::length(glm::cross(a0, m.axis)) <= tol::kParallel)
        throw Error("the axes are opposite: no one great circle joins them");
    Box box;
    box.expand(m.start);
    box.expand(m.end);
    for (int i = 0; i < 3; ++i) {
        double lo = std::min(a0[i], m.axis[i]), hi = std::max(a0[i], m.axis[i]);
        const double rho = std::hypot(a0[i], b[i]), phi = std::atan2(b[i], a0[i]);
        for (const double t : {phi, phi + kPi, phi - kPi, phi + 2 * kPi}) {
            if (t < 0.0 || t > theta) continue;
            lo = std::min(lo, rho * std::cos(t - phi));
            hi = std::max(hi, rho * std::cos(t - phi));
        }
        box.lo[i] -= reachAlong(-hi, -lo, length, radius);
        box.hi[i] += reachAlong(lo, hi, length, radius);
    }
    return box;
}

TurningSweep::TurningSweep(const Tool& tool, const Move& move, double epsilon)
    : tool_(tool), law_(move), epsilon_(epsilon) {
    if (!(epsilon >= kMinTurnTolerance) || !std::isfinite(epsilon)) {
        char text[200];
        std::snprintf(text, sizeof text, "the tolerance of a turning move's sweep must be at least %g mm, not %g",
                      kMinTurnTolerance, epsilon);
        throw Error(text);
    }
    bounds_ = turningMoveBox(move, tool.totalLength(), tool.maxRadius()).padded(kBoxSlack);
    // Every tool point lies within hypot(total length, max radius) of the tip.
    speed_ = law_.speedBound(std::hypot(tool.totalLength(), tool.maxRadius()));
    for (const ConvexPart& part : tool_.convexParts()) grownEpsilon_.push_back(offsetPart(tool_, part, epsilon_));
    for (int k = 0; k < kMaxLevel && std::ldexp(speed_, -(k + 1)) > epsilon_; ++k) {
        std::vector<std::vector<ProfilePiece>> level;
        for (const ConvexPart& part : tool_.convexParts())
            level.push_back(offsetPart(tool_, part, std::ldexp(speed_, -(k + 1)) - epsilon_));
        grown_.push_back(std::move(level));
    }
}

ToolPose TurningSweep::pose(double u) const { return law_.pose(u); }

Interval TurningSweep::bound(const Line& line) const { return lineInBox(line, bounds_.padded(epsilon_)); }

// Method. Write T(u) for the tool at pose(u) and V = speed().
//  (a) Speed. The motion is rigid (MotionLaw): on a great circle, a tool point moves as
//      y(u) = p(u) + R(u) (y0 - p0), with R(u) the turn by theta u about the fixed unit axis
//      k = a0 x a1 / |a0 x a1| (it carries a0 to a(u) along the great circle; the tool is a solid
//      of revolution, so which rotation about a(u) is chosen does not change T(u)). So
//      y'(u) = f + theta k x (y(u) - p(u)) and |y'| <= |f| + theta |y - p| <= V. A machine's
//      rotary move is bounded the same way turn by turn (MotionLaw::speedBound). Hence T(u') lies
//      within V |u' - u| of T(u): T(u') is inside T(u) grown by that.
//  (b) Depth. A point x deeper than epsilon inside T(u) has the ball B(x, epsilon) inside T(u);
//      the rigid motion from u to u' carries it to B(x', epsilon) inside T(u'), with
//      |x' - x| <= V |u' - u| = r. So x lies within r - epsilon of T(u') (of the point of the
//      ball nearest x) when r >= epsilon, and inside T(u') when r <= epsilon. The tool is a union
//      of convex parts, and growing distributes over the union: x lies in some part of T(u')
//      grown by max(r - epsilon, 0).
//  (c) Search. A node is a range [ua, ub] of width 2^-k whose two end poses have been solved
//      exactly (Tool::intersectPart per convex part); every u in it is within 2^-(k+1) of one of
//      them, so by (b) a point deeper than epsilon inside T(u) lies inside that end's tool grown
//      by g_k = r_k - epsilon, r_k = V 2^-(k+1). The grown tool is a convex solid of revolution
//      per part (offset.h); its interval along the line is exact. A node is settled when, at both
//      ends, the grown intervals hold no point of `care` outside the union O of the intervals
//      solved so far. A node whose reach r_k is at most epsilon is a leaf: g_k <= 0, so the ends'
//      own intervals, which O holds, hold those points. A node that is not settled, at a level
//      where g_k <= epsilon, is closed: its ends' grown intervals are added to O (each point of
//      them within epsilon of a pose). Otherwise the pose at the middle is solved, added to O, and
//      both halves are searched. The left half's test of the middle pose, passed, is the right
//      half's as well: O only grows.
//  (d) Gaps. Two consecutive intervals of O whose gap lies within the pose intervals grown by
//      epsilon (the pose that made the left one's upper end, and the right one's lower end) are
//      joined: every point of the gap is within epsilon of a pose, so within epsilon of S.
//  (e) Guarantees. O is a union of exact static intervals, intervals of poses grown by at most
//      epsilon (closed nodes) and such gaps, so every point of it is inside S or within epsilon of
//      it (1). A point x of `care` deeper than epsilon inside some T(u): u lies in a settled,
//      closed or leaf node, and x is in O by (c) (2).
//  (f) Cost. Settling needs the grown intervals inside O, so near a line's extreme the search
//      descends over the range of u where the tool's reach along the line is within
//      g_k / sin(angle) of its maximum, down to the level where g_k <= epsilon, two levels short
//      of a search that grew by r_k and stopped at r_k <= epsilon. Most nodes settle at once: far
//      from the tool the grown intervals are empty, and deep inside the cut they are held by the
//      neighbours' intervals.
std::vector<LineHit> TurningSweep::intersect(const Line& line, const std::vector<Interval>& care) const {
    std::vector<LineHit> out;
    const Interval reach = bound(line);
    if (reach.isEmpty()) return out;
    const Interval all[1] = {reach};
    const Interval* careBegin = care.empty() ? all : care.data();
    const Interval* careEnd = care.empty() ? all + 1 : care.data() + care.size();
    if (!std::any_of(careBegin, careEnd, [&](const Interval& c) { return !c.intersect(reach).isEmpty(); }))
        return out;

    const auto& parts = tool_.convexParts();
    Union found;
    auto solve = [&](double u) {
        const LocalLine local = LocalLine::make(pose(u), line);
        for (std::size_t p = 0; p < parts.size(); ++p) {
            const Interval iv = tool_.intersectPart(parts[p], local);
            if (!iv.isEmpty()) found.add(iv, u, p);
        }
        return local;
    };
    // Whether the tool at one end pose, grown by level k's reach, holds no point of care outside O.
    auto settled = [&](const LocalLine& local, int k) {
        for (const auto& grown : grown_[std::size_t(k)]) {
            const Interval g = intersectPieces(grown, local);
            if (g.isEmpty()) continue;
            for (const Interval* c = careBegin; c != careEnd; ++c) {
                const Interval part = g.intersect(*c);
                if (!part.isEmpty() && !found.holds(part.lo, part.hi)) return false;
            }
        }
        return true;
    };

    struct Node {
        double ua, ub;
        int level;
        LocalLine la, lb;
        bool aSettled;  ///< the end at ua passed this level's test (as its left sibling's end)
    };
    std::vector<Node> stack;
    stack.push_back({0.0, 1.0, 0, solve(0.0), solve(1.0), false});
    const int levels = int(grown_.size());
    while (!stack.empty()) {
        const Node n = stack.back();
        stack.pop_back();
        if (n.level >= levels) continue;  // a leaf: its reach is at most epsilon
        const std::size_t k = std::size_t(n.level);
        if ((n.aSettled || settled(n.la, n.level)) && settled(n.lb, n.level)) {
            // The right sibling, still on the stack, starts at this node's end.
            if (!stack.empty() && stack.back().level == n.level && stack.back().ua == n.ub) stack.back().aSettled = true;
            continue;
        }
        if (std::ldexp(speed_, -(n.level + 1)) - epsilon_ <= epsilon_) {  // closed: grown by at most epsilon
            for (std::size_t p = 0; p < parts.size(); ++p) {
                const Interval ga = intersectPieces(grown_[k][p], n.la);
                if (!ga.isEmpty()) found.add(ga, n.ua, p);
                const Interval gb = intersectPieces(grown_[k][p], n.lb);
                if (!gb.isEmpty()) found.add(gb, n.ub, p);
            }
            continue;
        }
        const double um = 0.5 * (n.ua + n.ub);
        const LocalLine lm = solve(um);
        stack.push_back({um, n.ub, n.level + 1, lm, n.lb, false});
        stack.push_back({n.ua, um, n.level + 1, n.la, lm, false});
    }

    // Close the gaps that lie within epsilon of the poses on both sides (d): where the line runs
    // nearly tangent to the envelope, consecutive poses' intervals leave slivers of 1e-7 mm that
    // the continuous motion sweeps, and that a stock must not keep.
    std::vector<Piece> pieces;
    for (const Piece& p : found.pieces()) {
        if (!pieces.empty()) {
            Piece& last = pieces.back();
            const Interval left = intersectPieces(grownEpsilon_[last.partHi], LocalLine::make(pose(last.uHi), line));
            const Interval right = intersectPieces(grownEpsilon_[p.partLo], LocalLine::make(pose(p.uLo), line));
            if (left.hi >= right.lo) {
                last.range.hi = p.range.hi, last.uHi = p.uHi, last.partHi = p.partHi;
                continue;
            }
        }
        pieces.push_back(p);
    }
    for (const Piece& p : pieces) {
        LineHit hit;
        hit.range = p.range;
        endNormal(line, p.range.lo, p.uLo, p.partLo, hit.normalLo, hit.sharpLo);
        endNormal(line, p.range.hi, p.uHi, p.partHi, hit.normalHi, hit.sharpHi);
        out.push_back(hit);
    }
    return out;
}

std::vector<Interval> TurningSweep::intersectAll(const Line& line) const {
    std::vector<Interval> out;
    for (const LineHit& h : intersect(line)) out.push_back(h.range);
    return out;
}

// The faces of one convex part at an end point: the bottom face (normal -a), the top face (+a)
// and the lateral pieces (meridianNormal). The nearest gives the normal; a second one within kRimReach tolerances
// whose normal differs puts the end on or near a rim of the pose's tool.
void TurningSweep::endNormal(const Line& line, double t, double u, std::size_t part, Vec3& normal,
                             bool& sharp) const {
    const ToolPose ps = pose(u);
    const ConvexPart& cp = tool_.convexParts()[part];
    const Vec3 d = line.at(t) - ps.tip;
    const double z = glm::dot(d, ps.axis);
    Vec3 radial = d - z * ps.axis;
    const double rho = glm::length(radial);
    if (rho > 0.0) {
        radial /= rho;
    } else {  // on the axis: any direction across it
        const Vec3 other = std::abs(ps.axis.x) < 0.9 ? Vec3(1.0, 0.0, 0.0) : Vec3(0.0, 1.0, 0.0);
        radial = glm::normalize(glm::cross(ps.axis, other));
    }
    struct Candidate {
        double gap;
        Vec3 n;
    };
    std::vector<Candidate> faces;
    faces.push_back({std::abs(z - cp.z0), -ps.axis});
    faces.push_back({std::abs(z - cp.z1), ps.axis});
    const auto& pieces = tool_.pieces();
    for (std::size_t i = cp.first; i < cp.last; ++i) {
        const double z0 = pieceZ0(pieces[i]), z1 = pieceZ1(pieces[i]);
        const double zc = std::clamp(z, z0, z1);
        const double R = pieceRadius(pieces[i], zc);
        double nr = 0.0, nz = 0.0;
        meridianNormal(pieces[i], R, zc, nr, nz);
        faces.push_back({std::hypot(rho - R, z - zc), nr * radial + nz * ps.axis});
    }
    std::sort(faces.begin(), faces.end(), [](const Candidate& a, const Candidate& b) { return a.gap < b.gap; });
    normal = faces[0].n;
    sharp = false;
    // The end's pose is within the search's reach of the pose that grazes there, so where the
    // envelope is swept by a rim, the end lies on a face of its pose near that rim, by about the
    // tolerance (along a face steep to the line, a few times it).
    const double nearRim = kRimReach * epsilon_;
    const Candidate* other = nullptr;
    for (std::size_t i = 1; i < faces.size() && faces[i].gap <= nearRim && !other; ++i)
        if (glm::dot(faces[i].n, normal) < std::cos(kRimAngle)) other = &faces[i];
    if (!other) return;
    // On a rim, a circle about the axis (on the axis, an apex: a point). Where the moving rim
    // grazes, the envelope is smooth there: its normal is across both the rim's tangent and the
    // rim point's velocity (MotionLaw::velocity), and lies within the rim's normal cone (the
    // normals between the two faces'). Elsewhere the end lies on a crease of the swept volume.
    const Vec3 n1 = normal, n2 = other->n;
    normal = glm::normalize(n1 + n2);
    sharp = true;
    if (rho <= 0.0) return;
    const Vec3 tangent = glm::cross(ps.axis, radial);
    const Vec3 velocity = law_.velocity(u, line.at(t));
    Vec3 n = glm::cross(tangent, velocity);
    const double len = glm::length(n);
    if (len <= tol::kParallel * glm::length(velocity)) return;
    n /= len;
    if (glm::dot(n, n1 + n2) < 0.0) n = -n;
    // n = alpha n1 + beta n2 in the meridian plane: inside the cone when both are non-negative.
    const double c = glm::dot(n1, n2), p1 = glm::dot(n, n1), p2 = glm::dot(n, n2);
    const double det = 1.0 - c * c;
    const double alpha = (p1 - c * p2) / det, beta = (p2 - c * p1) / det;
    if (alpha < 0.0 || beta < 0.0) return;
    normal = n;
    sharp = false;
}

}  // namespace dexelmill
