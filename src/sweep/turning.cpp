#include "dexelmill/sweep/turning.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>

#include <boost/container/small_vector.hpp>

#include "dexelmill/error.h"
#include "dexelmill/tool/offset.h"
#include "interpolation.h"
#include "turning_levels.h"

namespace dexelmill {

using turning::heapLevel;
using turning::heapWidth;
using turning::kMaxLevel;
using turning::kMaxLinearLevel;
using turning::nodePolynomialMax;
using turning::ParabolaLow;
using turning::parabolaLow;

namespace {

/// Slack (mm) on the box of the poses: keeps rounding of the box from cutting off a contact.
constexpr double kBoxSlack = 1e-9;

/// The settling test (note c) may take, for a grown torus that a line crosses, the interval of
/// cones tangent to it that lie within this fraction of the growth beyond it (outerOffsetPart): a
/// quarter-circle rim takes two (8.2 % out where they meet). Where more cones would be needed,
/// the root finding stops once it has the ends to within this fraction of the growth. Settling on
/// a larger interval fails more often, at most as a growth 10 % larger would. On BM_TurningQuery,
/// with cones in place of every torus, three or four a rim (slack 0.04 or 0.02) were slower than
/// two, and one (a square corner) far slower.
constexpr double kSettleSlack = 0.1;

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
/// made it, or the linear node (note h) whose move made it.
struct Piece {
    Interval range;
    double uLo = 0.0, uHi = 0.0;
    std::size_t partLo = 0, partHi = 0;
    /// The heap index of the linear node whose sweep made the end; 0 when a pose made it.
    std::uint32_t nodeLo = 0, nodeHi = 0;
};

/// A query's short lists, kept in place: most lines meet a tool in a few intervals and settle
/// with a few poses, and a heap allocation per list cost a tenth of a short move's query.
template <class T, std::size_t N = 8>
using ShortList = boost::container::small_vector<T, N>;

/// The union of static-pose intervals found so far: sorted, disjoint.
class Union {
  public:
    void add(const Interval& iv, double u, std::size_t part) { add(iv, u, u, part); }
    /// Adds an interval whose ends were made at different poses.
    void add(const Interval& iv, double uLo, double uHi, std::size_t part, std::uint32_t node = 0) {
        Piece p{iv, uLo, uHi, part, part, node, node};
        auto it = std::lower_bound(pieces_.begin(), pieces_.end(), iv.lo,
                                   [](const Piece& q, double lo) { return q.range.hi < lo; });
        // Merge every piece that overlaps or touches the new one.
        auto last = it;
        while (last != pieces_.end() && last->range.lo <= iv.hi) {
            if (last->range.lo < p.range.lo)
                p.range.lo = last->range.lo, p.uLo = last->uLo, p.partLo = last->partLo, p.nodeLo = last->nodeLo;
            if (last->range.hi > p.range.hi)
                p.range.hi = last->range.hi, p.uHi = last->uHi, p.partHi = last->partHi, p.nodeHi = last->nodeHi;
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
    const ShortList<Piece>& pieces() const { return pieces_; }

  private:
    ShortList<Piece> pieces_;
};

/// Most chords a ball's centre path is cut into; a move that needs more is searched whole.
constexpr double kMaxChords = 256.0;

/// The parameters of `line` (unit direction) within r of the segment [a, b]: one interval, since
/// the capsule is convex, the hull of the line's intervals in the two end balls and in the
/// cylinder between them (the points whose projection onto the segment falls inside it).
Interval lineCapsule(const Line& line, const Vec3& a, const Vec3& b, double r) {
    const auto inBall = [&](const Vec3& c) {
        const Vec3 oc = line.origin - c;
        const double half = glm::dot(line.dir, oc);
        const double disc = half * half - (glm::dot(oc, oc) - r * r);
        if (disc < 0.0) return Interval::empty();
        const double root = std::sqrt(disc);
        return Interval{-half - root, -half + root};
    };
    Interval out = inBall(a).hull(inBall(b));
    const Vec3 m = b - a;
    const double mm = glm::dot(m, m);
    if (!(mm > 0.0)) return out;
    // Across m, the line's offset from the segment's line is w(t) = oPerp + t dPerp.
    const Vec3 oa = line.origin - a;
    const double dm = glm::dot(line.dir, m), om = glm::dot(oa, m);
    const Vec3 dPerp = line.dir - (dm / mm) * m, oPerp = oa - (om / mm) * m;
    const Interval across =
        detail::solveQuadraticLE(glm::dot(dPerp, dPerp), glm::dot(dPerp, oPerp), glm::dot(oPerp, oPerp) - r * r).first;
    // Between the end planes: 0 <= om + t dm <= mm.
    Interval slab = Interval::all();
    if (dm == 0.0) {
        if (om < 0.0 || om > mm) slab = Interval::empty();
    } else {
        const double t0 = -om / dm, t1 = (mm - om) / dm;
        slab = {std::min(t0, t1), std::max(t0, t1)};
    }
    return out.hull(across.intersect(slab));
}

/// Whether convex part `part` (the tool's lowest) starts with a ball end: the lower half of a sphere (radius rho,
/// centre zc on the axis) from its bottom to its centre, then a cylinder of the same radius up
/// to at least zc + rho, so that the whole ball lies inside the part. Its radius must exceed
/// twice the tolerance (note g of TurningSweep::intersect).
bool ballEnd(const std::vector<ProfilePiece>& pieces, const ConvexPart& part, double epsilon, double& zc,
             double& rho) {
    if (part.last - part.first < 2) return false;
    const auto* arc = std::get_if<ArcPiece>(&pieces[part.first]);
    const auto* cylinder = std::get_if<ConePiece>(&pieces[part.first + 1]);
    if (!arc || !cylinder || arc->rc != 0.0 || arc->z0 != arc->zc - arc->rho || arc->z1 != arc->zc) return false;
    if (cylinder->z0 != arc->zc || cylinder->r0 != arc->rho || cylinder->r1 != arc->rho ||
        cylinder->z1 < arc->zc + arc->rho)
        return false;
    if (!(arc->rho > 2.0 * epsilon)) return false;
    zc = arc->zc;
    rho = arc->rho;
    return true;
}

/// Most regula falsi steps note k takes towards the pose where a line passes through a rim, and
/// how near the rim's radius (mm) the line's crossing of its plane must come to stop sooner.
constexpr int kCornerSteps = 12;
constexpr double kCornerGap = 1e-9;

/// Most regula falsi steps note l takes towards the pose where a line's end stops growing.
constexpr int kGrazeSteps = 4;

/// Regula falsi with the Illinois step on [ua, ub], where fa and fb have opposite signs: `at(u)`
/// is called at each new point, at most `steps` times, and returns the function's value there, or
/// none to stop. Where the same end moves twice in a row, the other end's value is halved, so
/// that a convex function's root is not approached from one side only.
template <class At>
void regulaFalsi(double ua, double ub, double fa, double fb, int steps, At&& at) {
    int moved = 0;  // which end the last step moved: 1 the lower, -1 the upper
    for (int step = 0; step < steps; ++step) {
        const double u = ua + (ub - ua) * fa / (fa - fb);
        const std::optional<double> fu = at(u);
        if (!fu) return;
        if ((*fu > 0.0) == (fa > 0.0)) {
            ua = u, fa = *fu;
            if (moved == 1) fb *= 0.5;
            moved = 1;
        } else {
            ub = u, fb = *fu;
            if (moved == -1) fa *= 0.5;
            moved = -1;
        }
    }
}

}  // namespace

TurningSweep::TurningSweep(const Tool& tool, const Move& move, double epsilon)
    : tool_(tool), law_(move), epsilon_(epsilon) {
    if (!(epsilon >= kMinTurnTolerance) || !std::isfinite(epsilon)) {
        char text[200];
        std::snprintf(text, sizeof text, "the tolerance of a turning move's sweep must be at least %g mm, not %g",
                      kMinTurnTolerance, epsilon);
        throw Error(text);
    }
    bounds_ = turningMoveBox(move, tool.bottom(), tool.totalLength(), tool.maxRadius()).padded(kBoxSlack);
    // Every tool point lies within hypot(total length, max radius) of the tip (note a).
    axisTurn_ = law_.axisTurnBound();
    tipSpeed_ = law_.speedBound(0.0);
    axisBend_ = law_.axisPointAccelerationBound(1.0);
    axisJerk_ = law_.axisJerkBound();
    const double reach = std::hypot(tool.totalLength(), tool.maxRadius());
    speed_ = std::min(law_.speedBound(reach), law_.speedBound(0.0) + axisTurn_ * reach);
    // A ball end at the bottom (note g): chords enough that w^2 / 8 |c''| <= epsilon / 2 for
    // chords of width w = 1 / chords, i.e. chords^2 >= |c''| / (4 epsilon).
    parts_ = tool_.convexParts();
    Ball ball;
    if (!parts_.empty() && ballEnd(tool_.pieces(), parts_.front(), epsilon_, ball.zc, ball.rho)) {
        const double accel = law_.axisPointAccelerationBound(ball.zc);
        const double chords = std::max(1.0, std::ceil(std::sqrt(accel / (4.0 * epsilon_))));
        if (chords <= kMaxChords) {
            chords_ = int(chords);
            const ConvexPart bottom = parts_.front();
            parts_.front() = {bottom.first + 1, bottom.last, ball.zc, bottom.z1};
            balls_.push_back(std::move(ball));
        }
    }
    for (Ball& ball : balls_)
        for (int j = 0; j <= chords_; ++j) {
            const ToolPose p = law_.pose(double(j) / chords_);
            ball.centres.push_back(p.tip + ball.zc * p.axis);
        }
    for (const ConvexPart& part : parts_) {
        grownEpsilon_.push_back(offsetPart(tool_, part, epsilon_));
        faces_.push_back(meridianFaces(tool_.pieces(), part));
    }
    for (const Ball& ball : balls_) {
        const double r = ball.rho + epsilon_;
        grownEpsilon_.push_back({ArcPiece{ball.zc - r, ball.zc + r, 0.0, ball.zc, r}});
    }
    startPhase_ = law_.phase(0.0);
    endPhase_ = law_.phase(1.0);
    startPose_ = law_.pose(startPhase_);
    endPose_ = law_.pose(endPhase_);
    startTwist_ = law_.twist(startPhase_);
    endTwist_ = law_.twist(endPhase_);
    midPhase_ = law_.phase(0.5);
    midPose_ = law_.pose(midPhase_);
    // The static search closes its nodes from the first level whose growth is at most epsilon.
    while (closingLevel_ < kMaxLevel && std::ldexp(speed_, -(closingLevel_ + 1)) > 2.0 * epsilon_) ++closingLevel_;
    chooseLinearNodes();
    if (!models_.empty()) return;
    for (int k = 0; k < kMaxLevel && std::ldexp(speed_, -(k + 1)) > epsilon_; ++k) {
        const double g = std::ldexp(speed_, -(k + 1)) - epsilon_;
        std::vector<OuterPart> level;
        for (const ConvexPart& part : parts_) level.push_back(outerOffsetPart(tool_, part, g, kSettleSlack * g));
        grown_.push_back(std::move(level));
        halfSteps_.push_back(law_.step(std::ldexp(1.0, -(k + 1))));
    }
}

ToolPose TurningSweep::pose(double u) const { return law_.pose(u); }

Interval TurningSweep::bound(const Line& line) const {
    if (outer_.empty()) return lineInBox(line, bounds_.padded(epsilon_));
    Interval hull;
    for (const MoveSweep& part : outer_) hull = hull.hull(part.bound(line));
    return hull;
}

// Method. Write T(u) for the tool at pose(u) and V = speed().
//  (a) Speed. The motion is rigid (MotionLaw): on a great circle, a tool point moves as
//      y(u) = p(u) + R(u) (y0 - p0), with R(u) the turn by theta u about the fixed unit axis
//      k = a0 x a1 / |a0 x a1| (it carries a0 to a(u) along the great circle; the tool is a solid
//      of revolution, so which rotation about a(u) is chosen does not change T(u)). So
//      y'(u) = f + theta k x (y(u) - p(u)) and |y'| <= |f| + theta |y - p| <= V. A machine's
//      rotary move is bounded the same way turn by turn (MotionLaw::speedBound), but its turns
//      may also spin the tool about its own axis (a rotary table under an upright tool), which
//      does not move the solid. So V is at most the tip's speed bound plus omega_a d, omega_a
//      bounding how fast the axis's direction turns (MotionLaw::axisTurnBound, theta on a great
//      circle) and d a tool point's largest distance from the tip: the rigid motion
//      y -> p(u') + N (y - p(u)), N the least rotation carrying a(u) to a(u'), maps T(u) onto
//      T(u') and moves y by at most |p(u') - p(u)| + angle(a(u), a(u')) d. Hence T(u') lies
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
//      solved so far. The test is made piece by piece on intervals that hold each piece's
//      (allPiecesHeld: a torus's slab within its outer cylinder first, then where it would need
//      root finding its tangent cones, within kSettleSlack g_k of it, or where those would be too
//      many its ends found to within kSettleSlack g_k, from outside): what a larger interval
//      leaves outside O, a smaller one does too. A node whose reach r_k is
//      at most epsilon is a leaf: g_k <= 0, so the ends' own intervals, which O holds, hold those
//      points. A node that is not settled, at a level where g_k <= epsilon, is closed: its ends'
//      grown intervals are added to O (each point of them within epsilon of a pose). Otherwise the
//      pose at the middle is solved, added to O, and both halves are searched. The middle pose
//      is stepped from the start's by the angle sum (MotionLaw::advance), not made from its own
//      sines and cosines: after at most kMaxLevel steps it lies within 60 n d kPhaseStepError of
//      the exact pose (n turns, d a tool point's distance from a pivot), 1.6e-10 mm for n = 3 and
//      d = 1 m. A solved end that far from its pose moves (b)'s reach by as much: guarantee 2
//      holds for points deeper than epsilon + 1.6e-10 mm, a difference four orders below the
//      finest epsilon and the spacing of the stock's float ends (8e-6 mm at 100 mm). The left half's
//      test of the middle pose, passed, is the right half's as well: O only grows.
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
//  (g) Ball ends. When the tool's lowest convex part is a ball end (ballEnd: the lower
//      half-sphere of radius R about the axis point at height zc, then a cylinder of radius R up
//      to at least zc + R), the tool is the union of the whole ball B and P, the tool above zc
//      (that part above zc and every part over it); the search runs on P's convex parts alone,
//      and B's sweep is taken as capsules. B's centre moves on
//      c(u) = p(u) + zc a(u), with |c''| <= K (MotionLaw::axisPointAccelerationBound). On a chord
//      from c(u_j) to c(u_j + w), the straight interpolant L(u) has |c(u) - L(u)| <= w^2 K / 8
//      (along any fixed direction, the error is a scalar function that vanishes at both ends,
//      whose second derivative is at most K); w is chosen so that this is at most
//      delta = epsilon / 2. The union of the capsules of radius R about the chords is then
//      within delta of the union of the balls B(u) (a point within R of L(u) is within R + delta
//      of c(u)), and holds every point deeper than delta inside some B(u) (|x - c(u)| <= R - delta
//      puts x within R of L(u)). So the capsules keep guarantee 1, and guarantee 2 holds if every
//      point x deeper than epsilon inside T(u) is deeper than delta inside B(u) or deeper than
//      epsilon inside P(u). With z the height of x above the centre and rho its distance from the
//      axis: if z < 0, the point of the sphere nearest x lies on the lower half, a face of T, so
//      x's depth in B is at least its depth in T; if z > epsilon, its depth in P is the smaller
//      of its depth in T and z (P is T cut by the plane at the centre's height); if 0 <= z <= epsilon, the cylinder
//      bounds rho <= R - epsilon, so |x - c| <= sqrt((R - epsilon)^2 + epsilon^2) and x's depth
//      in B is more than epsilon / 2 whenever R > 7 epsilon / 4 (ballEnd asks for R > 2 epsilon).
//      The search settles P's nodes against O with the capsules already in it: near the ball's
//      surface P's grown intervals are empty or held, so the search descends only where P
//      itself comes near the line. A move whose law has no bound K (a tip the machine carries)
//      or would need more than kMaxChords chords is searched whole.
//  (h) Linear nodes. Where the tip runs on a straight line (an APT MULTAX move, a machine's move
//      under tool centre point control), the tip's travel |f| is most of V on a typical move, and
//      the search above pays for it at every level. A node can instead be taken as a fixed-axis
//      linear move, which MoveSweep sweeps in closed form: the tool's axis point at height zc
//      (the pivot, the middle of the part's heights) runs on the chord from c(ua) to c(ub), with
//      c(u) = p(u) + zc a(u), and the axis is held at a(um), um the node's middle. Its pose M(u)
//      is carried to T(u) by a rigid motion that moves a tool point at distance rho from the pivot
//      by at most |c(u) - L(u)| + |N - I| rho <= K w^2 / 8 + omega (w / 2) rho = delta_k, for a
//      node of width w = 2^-k: L is the chord (its error as in g, with K =
//      MotionLaw::axisPointAccelerationBound(zc)), N the least rotation carrying a(um) to a(u) (the
//      solid of revolution is the same whichever rotation about a(u) poses it), whose angle is at
//      most omega (w / 2), omega = MotionLaw::axisTurnBound, and rho at most hypot(half the part's
//      height, its largest radius). As in (b), with M(u) in place of T(u'), a point deeper than
//      epsilon inside T(u) lies inside M(u) grown by max(delta_k - epsilon, 0), and every point of
//      M(u) lies within delta_k of T(u). The search runs part by part (band by band, note i); the
//      static poses at u = 0 and 1 go into O when the root does not settle without them. A node
//      whose delta_k is at most epsilon is a leaf: the part's sweep along its move goes into O,
//      within epsilon of S (1) and holding every point deeper than epsilon inside T(u) for u in the
//      node (2). Any other node is settled when the part grown by delta_k - epsilon
//      (mitredOffsetPart, a superset) swept along its move holds no point of care outside O;
//      otherwise the static pose at its middle goes into O and both halves are searched. Every u
//      lies in a settled node or a leaf, so (2) holds; O holds static poses and leaves' sweeps, so
//      (1) holds. The gaps of (d) are closed between poses' ends only: a leaf's sweep already holds
//      every point deeper than epsilon inside its node's poses.
//      Cost: the reach falls as omega rho 2^-(k+1) instead of V 2^-(k+1), so the leaves lie
//      about log2(V / (2 omega rho)) levels higher than the closing level of (c), and near a
//      graze of the envelope the nodes a level are fewer by about the square root of that ratio.
//      A node's sweep is made once per move, by the first query that needs it, and kept
//      (NodeCache, within the budget of every sweep alive) down to kMaxKeptLevel; deeper nodes,
//      which few lines share, are made by each query and dropped. Making one costs far more than
//      solving a pose, so a move takes linear nodes only when its leaves lie at least
//      kLinearLevelsSaved levels above the closing level of (c), and no deeper than
//      kMaxLinearLevel; it keeps the search of (c) otherwise.
//  (i) Bands. A line that meets the tool near its tip needs (h)'s bound only for the tool points
//      near it, but rho bounds every point of the part from its one pivot: half the length of a
//      long cutter. So each part is cut into bands of heights, each searched as (h) searches a
//      part with its own pivot at its middle, rho_b = hypot(half its height, its largest radius)
//      (on a flat D10 x 50, about 5.6 mm against 25.5). A band [zb0, zb1] is grown by epsilon at
//      each end where it is cut (clipChain to [zb0 - epsilon, zb1 + epsilon]; the part's own ends
//      stay), and (h)'s argument holds for it as for a part: a point x deeper than epsilon inside
//      T(u), at a height of band b, is carried by band b's rigid motion to x' with
//      |x - x'| <= delta_b, and the ball of radius epsilon about x' lies in the carried tool; the
//      point of that ball nearest x (within delta_b - epsilon of x when delta_b > epsilon, x
//      itself otherwise) lies within epsilon of x' in the tool's frame, so at a height of the
//      grown band. So x lies inside the grown band carried and grown by max(delta_b - epsilon, 0):
//      in a settled node's grown sweep, or in a leaf's. Every point of a leaf's sweep lies within
//      delta_b <= epsilon of a pose, as in (h). Where a node is not settled, the static pose at
//      its middle goes into O for the whole part, so every node's two ends are in O (they are
//      its ancestors' middles, or u = 0 and 1): inside the tool, where a band's grown sweep
//      reaches past its cut into the next band's heights, those poses hold it, and only near the
//      envelope does each band descend. The leaves lie about log2(rho / rho_b) levels higher, and
//      near a graze of the envelope, where the nodes a level grow by about the square root of 2
//      per level, the search costs about the square root of rho / rho_b less. The cost of
//      starting several searches per line is kept off lines far from the part by first testing
//      the part's root whole ((h)'s node of level 0, wholeRoots_): when it settles, so does every
//      band. A part is cut only where its bands' leaves lie kBandLevelsSaved levels above its
//      own, and where note j's anchored nodes settle nodes only from kBandAnchorLevel down. An
//      end that a band's leaf makes takes the Hermite data of the whole part at the true pose
//      where the leaf's move makes it (nodeEndNormal), so a face where the band was cut (inside
//      the tool, met only within epsilon of its rim on the envelope) gives no normal.
//  (j) Anchored nodes. A node of (h) that does not settle may still be settled by the faces of
//      its end poses a and b (in O: its ancestors' middles, or u = 0 and 1), with a bound of
//      second order in its width w. Let y be where the line leaves (enters) the part at pose e,
//      the end of that pose's interval, and n the part's outward normal there, so that the part
//      lies in the half-space {z : n.(z - y) <= 0}. For u in the node, T(u) is the image of the
//      part at e under g: z -> c(u) + N (z - c(e)), with c the axis point at y's height h and N
//      the least rotation carrying a(e) to a(u) (any rotation onto a(u) poses the same solid).
//      So a point z deeper than epsilon inside T(u) has n_u.(z - y_u) <= -epsilon, n_u = N n,
//      y_u = g(y). With tau = |u - e| <= w, and z = y + s d beyond y (y - s d before it), s >= 0:
//        s |n.d| = n.(z - y) = n_u.(z - y_u) + (n - n_u).(z - y_u) + n.(y_u - y)
//                <= -epsilon + omega tau (s + V_y tau) + n.(y_u - y),
//      as N turns by at most omega tau (omega = MotionLaw::axisTurnBound) and |y_u - y| <= V_y tau,
//      V_y = |f| + omega (|h| + r) bounding the speed of c and of N about it, r = y's distance
//      from the axis. And c(u) - c(e) strays from its tangent +-tau c'(e) by at most K tau^2 / 2
//      (K = MotionLaw::axisPointAccelerationBound(|h|)); with q = y - c(e) (|q| = r),
//      (N - I) q = m x q + (1 - cos phi) k x (k x q), where m = a(e) x a(u) = sin(phi) k strays
//      from +-tau a(e) x a'(e) by at most |a''| tau^2 / 2 (|a''| <= axisPointAccelerationBound(1))
//      and 1 - cos phi <= omega^2 tau^2 / 2. So n.(y_u - y) <= +-tau n.v + (K + (|a''| + omega^2)
//      r) tau^2 / 2, where v = c'(e) + (a x a') x q differs from the law's velocity at y
//      (MotionLaw::velocity) by a spin about the axis, which moves y across the meridian plane n
//      lies in: n.v is the same. In all, s |n.d| <= -epsilon + tau (+-n.v + omega s) + C tau^2 with
//      C = omega V_y + (K + (|a''| + omega^2) r) / 2, the sign + for a (u after it) and - for b.
//      The right side is convex in tau, so largest at tau = 0 (-epsilon, below s |n.d|) or w:
//      where |n.d| >= omega w and +-w n.v + C w^2 < epsilon, no point of the line beyond y is
//      deeper than epsilon inside any T(u) of the node. The node is settled when its grown sweep,
//      cut at such crossings, holds no point of care outside O. The plane passes through the
//      end the static solve found, with the normal of the face nearest it (faceNormal), so the
//      cut is as exact as that solve.
//      The bound is on depth inside the one part. That is what guarantee 2 asks of a tool of one
//      convex part, and of the part above a ball end's ball (g); a tool of several parts may hold
//      a point deeper than epsilon near a joint that is as deep in none of them ((b) and (h) give
//      such a point to a part it lies near), so the anchored test is taken only where the
//      search has one part.
//      Cost: the bound is of second order where the face is still (n.v = 0 where a pose grazes
//      the envelope) and holds at any width where the face retreats from the crossing. So near a
//      graze the descent stops where C w^2 reaches epsilon rather than where (h)'s reach
//      omega rho_b w / 2 does, and a face that leads the tool to the first or last pose (its front
//      in uncut stock at u = 1) stops it at once, where (h) walked down to a leaf. A node's
//      crossings are found only for the side of its grown sweep that O leaves open, and each
//      pose's once.
//  (k) Corners. Where the line's end on one side is made by a rim of the part (two faces meeting
//      at an angle, such as a flat end's bottom edge), the end stops growing at the pose where
//      the line passes through the rim, with a kink: (j) settles the nodes around that pose only
//      where an anchor lies within epsilon / |n.v| of it, about log2(|n.v| / epsilon) levels
//      down. So where (j) bounds neither side and the crossings at the node's two ends lie on
//      two faces that meet at a rim (faceNormal's indices k and k + 1, Rim), that pose is found:
//      g(u), how far outside the rim's radius the line crosses the rim's plane at pose u, has
//      opposite signs at the ends, and regula falsi (Illinois) brings it within kCornerGap in at
//      most kCornerSteps steps. The pose u_c there is solved and goes into O. Let y be its end
//      on that side and r the rim's point nearest y, gap = |y - r|. Each face's plane through r,
//      normal n_f, holds the part, so (j)'s argument holds with r in place of y: for z = y + s d
//      beyond y, s |n.d| <= n.(z - r) + gap and |z - r| <= s + gap, so
//        s (|n.d| - omega tau) <= -epsilon + gap (1 + omega tau) +- tau n_f.v + C tau^2,
//      with v the velocity of the tool point at r and C (j)'s bound at r's height and radius.
//      The right side is convex in tau: where it is negative at tau = 0 (gap < epsilon) and at
//      tau = w, and |n_f.d| >= omega w, no point beyond y is deeper than epsilon in any T(u)
//      with |u - u_c| <= w on that side of u_c. The node is settled on that side when one face
//      does so back to its start (the sign -) and one, the same or the other, on to its end
//      (+), and its grown sweep cut at y is held.
//      Cost: past the kink each face's normal speed keeps its sign, so each bounds a wide node
//      at first order; a z-line meeting a flat end's bottom rim settles at the node whose end
//      poses straddle the kink, a few regula falsi steps of a pose and a few dot products each.
//  (l) Grazes. Where the end on one side grows at pose a (n.v > 0 at its crossing, in (j)'s
//      sense) and shrinks at b (n.v < 0), it stops growing at a pose between them. On a curved
//      face the end's curvature in u is large (about |f|^2 / rho on a torus of radius rho), so
//      (j) settles the nodes around that pose only where an anchor lies within about
//      sqrt(epsilon / curvature) of it: level 10 for a bull nose on BM_TurningQuery's 32 mm move.
//      So where (j) bounds neither side, and the node is narrow enough that (j)'s bound from a
//      pose in its middle could hold (C w^2 < 4 epsilon, C the larger of the two crossings'),
//      regula falsi (Illinois) on n.v, each step a solved pose that goes into O, looks for that
//      pose in at most kGrazeSteps steps. A pose u_g whose crossing meets (j)'s condition back
//      to a (width u_g - a, sign -) and on to b (width b - u_g, sign +), with |n.d| at least
//      omega times the larger width, bounds the points beyond its end over the whole node by
//      (j)'s argument, and the node is settled on that side. On BM_TurningQuery's bull nose the
//      first level narrow enough settles so, with two steps.
//  (m) Both ends. Where neither end pose bounds a side of the node over its whole width, the two
//      may share it: (j)'s argument from pose e, for the points beyond H, the end of the hull of
//      both poses' intervals on that side, rather than beyond e's own end y. A point z = y + s d
//      beyond H has s >= D, D >= 0 the distance from y to H along the line, so where
//      |n.d| >= omega tau, (j)'s inequality s (|n.d| - omega tau) <= -epsilon +- tau n.v + C tau^2
//      fails for every such s when
//        G(tau) = epsilon + D |n.d| - tau (D omega +- n.v) - C tau^2 > 0.
//      G is concave and G(0) > 0, so it holds on [0, tau_e) up to its positive root, which with
//      |n.d| / omega bounds the stretch of the node next to e that e's crossing bounds. Where
//      tau_a + tau_b > w, every u of the node lies in one of the two stretches, and no point of
//      the line beyond H is deeper than epsilon inside any T(u): the node is settled on that
//      side when its grown sweep cut at H is held. (j) is the case D = 0 with tau_e >= w.
//      Cost: where the end moves the same way at both poses, the nearer pose's slack D is about
//      w |n.v|, and the pair bounds nodes about twice as wide as either alone; where it dips
//      between them (n.v < 0 at a and > 0 at b), each bounds about |n.v| / C. On boat-xyzac at
//      h = 0.5 mm it took the middle poses solved from 531,000 to 369,000.
//  (n) Nodes without their sweep. (j) and (m) ask of a node's grown sweep only that it hold every
//      point of care deeper than epsilon inside the node's poses: beyond a bounded side it is cut
//      away, and between the sides what is left must be in O. The whole line does too, so a node
//      below the root whose end poses bound each side where care reaches beyond their intervals
//      outside O, and whose stretch between them O holds, is settled before its sweep is made
//      or intersected (a caller that clips care to bound(line), as the cutting loop does, leaves
//      no care where the sweep cannot be). Only (j) and (m) are tried there; where they fail,
//      the node takes its sweep and the test of (j) to (l) as before. On BM_TurningQuery's bull
//      nose at 1 degree: 23,300 -> 19,300 instructions a line; boat-xyzac's cut 7 % less.
//      The root, the whole move (w = 1, its end poses u = 0 and 1), is tried so too, before its
//      sweep, unless a ball's capsules (g) come first: the cutting loop queries a line only
//      where bound(line) meets its material, so most lines queried meet the tool, and two
//      static solves cost less than the root's grown sweep, which a line settled so never
//      needs (BM_TurningShortQuery: bull nose 446 -> 329 ns a line, flat end 161 -> 149).
//      Below a ball end, whose capsules hold most lines that reach the part above, the root's
//      sweep comes first: held there, it needs no pose solved (solving the ends first made the
//      ball's short rows 1.5 times slower). Where the end poses leave the root of a part searched
//      whole open, it is split without its sweep (a node's test is optional: one not tried is
//      split, as one that fails): BM_TurningShortQuery's flat end 104 -> 102 ns a line at 0.2
//      degrees, 125 -> 120 at 0.6.
//  (o) Disks and cylinders. Where a line's end on one side lies on a disk face (a flat end's
//      bottom, a part's top) at both end poses of a node and the end moves outward from one of them
//      and back before the other (a dip in u), (j) to (m) bound that side only from poses within
//      sqrt(epsilon / C) of the dip's deepest pose: on boat-xyzac, four lines in five of those the
//      root left open, each then taking three to five middle poses and their nodes' sweeps. But a
//      disk's plane is known at every pose, and a convex part lies behind it: with n(u) = s a(u)
//      (s = -1 for the bottom disk, 1 for the top) and c(u) = p(u) + h a(u) its centre at height h,
//      a point z is deeper than epsilon inside T(u) only if H_z(u) = n(u).(z - c(u)) <= -epsilon.
//      H_z(u) = s (a(u).(z - p(u)) - h) is a smooth function of u alone, and where the tip runs on
//      a straight line (p'' = 0, as note j asks) H''' = s (a'''.(z - p) - 3 a''.f), so
//      |H'''| <= M = J |z - p|max + 3 K1 |f|, with J >= |a'''| (MotionLaw::axisJerkBound), K1 >=
//      |a''| (axisPointAccelerationBound(1)) and |z - p(u)| largest at an end of the tip's segment.
//      The parabola P through H_z at three poses u_0 < u_1 < u_2 (the node's ends and a pose
//      between) strays from H_z on [u_0, u_2] by at most M |(u - u_0)(u - u_1)(u - u_2)| / 6, the
//      interpolation remainder, whose largest is at a root of its derivative. So where P's least on
//      the node, less that remainder, exceeds -epsilon, no T(u) of the node holds z deeper than
//      epsilon. Beyond z along the line, H grows at the rate n(u).d, which stays positive where the
//      end poses' |n.d| exceed omega w / 2 (each u lies within w / 2 of one). Taking z at the
//      farthest end of the three poses' intervals on that side, which O holds, the node is settled
//      on that side as in (j). The search takes z at the end poses' farther end and the node's
//      middle pose (its H only, no interval solved) first: where the end does not dip past z that
//      settles; otherwise the pose at the vertex of that parabola, the dip's deepest to within the
//      remainder, is solved and goes into O, and the test is made again with it in the middle. The
//      remainder is of third order in w and small where the axis turns little, so most such lines
//      settle at the root: H at three poses and one pose solved, where (j) descended three to five
//      levels. A rotary table turning under a tilted tool swings the disk's plane round, so its
//      ends dip often: boat-xyzac's cut (one thread, h = 0.5 mm) 0.320 -> 0.206 s, boat-xyzbc's
//      0.540 -> 0.436 s. A great circle tilts the disk one way, and BM_TurningQuery's and
//      BM_TurningShortQuery's lines seldom dip there.
//      Cylinders. A convex part whose side is a cylinder of radius R lies within R of its axis (its
//      radius, concave in z, is largest where it is constant), so z is deeper than epsilon inside
//      T(u) only if G_z(u) = |z - p|^2 - (a.(z - p))^2 - R^2 <= (R - epsilon)^2 - R^2. With
//      q = a.(z - p): G''' = -(q^2)''' = -(2 q q''' + 6 q' q''), where |q| <= r = max |z - p|,
//      |q'| <= omega r + |f|, |q''| <= K1 r + 2 omega |f| and |q'''| <= J r + 3 K1 |f|; so the same
//      test holds with M = 2 r (J r + 3 K1 |f|) + 6 (omega r + |f|)(K1 r + 2 omega |f|). Beyond z,
//      G_{z + s e}(u) is convex in s with slope 2 g(u) at s = 0, g(u) = (z - p).e - q (a.e) (e the
//      direction beyond), and |g'| <= 2 (|f| + omega r): where g at a and b exceeds
//      (|f| + omega r) w, g stays positive over the node and G only grows beyond z. On boat-xyzbc,
//      where the sides' ends dip most (three in five of the lines the root left open), its cut
//      0.436 -> 0.376 s; BM_TurningShortQuery's flat end 102 -> 96 ns a line at 0.2 degrees, 118 ->
//      107 at 0.6.
std::vector<LineHit> TurningSweep::intersect(const Line& line, const std::vector<Interval>& care) const {
    std::vector<LineHit> out;
    intersect(line, care, out);
    return out;
}

void TurningSweep::intersect(const Line& line, const std::vector<Interval>& care, std::vector<LineHit>& out) const {
    out.clear();
    // Without a care, the answer matters wherever the sweep may be: within the line's bound.
    Interval all[1] = {Interval::all()};
    if (care.empty()) {
        all[0] = bound(line);
        if (all[0].isEmpty()) return;
    }
    const Interval* careBegin = care.empty() ? all : care.data();
    const Interval* careEnd = care.empty() ? all + 1 : care.data() + care.size();
    // Every output interval lies within the parts' grown sweeps (outer_, bound()), so a line
    // whose care misses their narrowed bounds has none: one that passes a box of theirs beside
    // the tool, in a corner. On BM_TurningShortQuery that is a third of the lines the cutting
    // loop asks about, each of which solved both end poses and the root's sweep to find nothing
    // (bull nose 294 -> 260 ns a line, flat end 116 -> 112). A ball's capsules (g) turn such
    // lines away for about what the test costs, so a ball end skips it.
    const Interval within = careBegin->hull(careEnd[-1]);  // care is sorted
    if (!outer_.empty() && balls_.empty()) {
        Interval near;
        for (const MoveSweep& part : outer_) near = near.hull(part.narrowBound(line, within));
        if (std::none_of(careBegin, careEnd, [&](const Interval& c) { return !c.intersect(near).isEmpty(); }))
            return;
    }

    const auto& parts = parts_;
    Union found;
    // The balls' capsules (g); each end's pose is where its chord comes nearest it.
    for (std::size_t b = 0; b < balls_.size(); ++b) {
        const std::vector<Vec3>& c = balls_[b].centres;
        for (int j = 0; j < chords_; ++j) {
            const Interval iv = lineCapsule(line, c[std::size_t(j)], c[std::size_t(j) + 1], balls_[b].rho);
            if (iv.isEmpty()) continue;
            const Vec3 m = c[std::size_t(j) + 1] - c[std::size_t(j)];
            const double mm = glm::dot(m, m);
            const auto chordU = [&](double t) {
                const double s = mm > 0.0 ? std::clamp(glm::dot(line.at(t) - c[std::size_t(j)], m) / mm, 0.0, 1.0) : 0.0;
                return (j + s) / chords_;
            };
            found.add(iv, chordU(iv.lo), chordU(iv.hi), parts.size() + b);
        }
    }
    // Whether `g` holds no point of care outside O.
    const auto held = [&](const Interval& g) {
        for (const Interval* c = careBegin; c != careEnd && !g.isEmpty(); ++c) {
            const Interval part = g.intersect(*c);
            if (!part.isEmpty() && !found.holds(part.lo, part.hi)) return false;
        }
        return true;
    };
    if (!models_.empty()) {
        // Linear nodes (notes h and i), band by band from the root down. The static poses of a
        // band's part at both ends go into O where the root's sweep is not held without them (a
        // line the grown band's sweep misses, or that a ball's capsules already hold, needs
        // neither); the static pose at a node's middle is its whole part's too.
        std::optional<LocalLine> atStart, atEnd;
        std::size_t endsAdded = parts.size();  // the part whose end poses are in O already
        // A static pose of the part in O at u, its interval, and per end of it (lower, upper) what
        // note j asks of the face the line crosses there, found when first needed. The first two
        // are the part's at u = 0 and 1, then a band's nodes' middles.
        struct Crossing {
            bool found = false;
            double across = 0.0;  ///< n.d: the face's outward normal n along the line
            double speed = 0.0;   ///< n.v, v the velocity of the tool point there
            double bend = 0.0;    ///< C: how far the face's supporting plane strays in second order
            int face = 0;         ///< the face's index up the meridian (faceNormal)
        };
        struct Solved {
            double u = 0.0;
            ToolPose pose;
            Interval range;
            Crossing ends[2];
            TurnPhase phase;  ///< u's, which the velocities take
        };
        // Made by the first addEnds (most lines settle at a root), kept per thread so that a query
        // allocates nothing once its thread has seen one as deep.
        static thread_local std::vector<Solved> solved;
        solved.clear();
        const auto addEnds = [&](std::size_t p) {
            if (!atStart) atStart = LocalLine::make(startPose_, line), atEnd = LocalLine::make(endPose_, line);
            const Interval first = tool_.intersectPart(parts[p], *atStart);
            const Interval last = tool_.intersectPart(parts[p], *atEnd);
            if (!first.isEmpty()) found.add(first, 0.0, p);
            if (!last.isEmpty()) found.add(last, 1.0, p);
            endsAdded = p;
            solved.clear();
            solved.push_back({startPhase_.u, startPose_, first, {}, startPhase_});
            solved.push_back({endPhase_.u, endPose_, last, {}, endPhase_});
        };
        // Note j's C for a tool point at `height` above the tip and `off` from the axis.
        const auto bendAt = [&](double height, double off) {
            const double turn = axisTurn_;
            const double pivotSpeed = tipSpeed_ + turn * std::abs(height);
            return turn * (pivotSpeed + turn * off) +
                   0.5 * (law_.axisPointAccelerationBound(std::abs(height)) + (axisBend_ + turn * turn) * off);
        };
        const auto crossing = [&](Solved& pose, std::size_t p, int upper) -> const Crossing& {
            Crossing& c = pose.ends[upper];
            if (c.found) return c;
            const Vec3 y = line.at(upper ? pose.range.hi : pose.range.lo);
            const Vec3 n = faceNormal(pose.pose, p, y, &c.face);
            const double height = glm::dot(y - pose.pose.tip, pose.pose.axis);
            const double off = glm::length(y - pose.pose.tip - height * pose.pose.axis);
            c.found = true;
            c.across = glm::dot(n, line.dir);
            const Vec3 velocity = pose.u == startPhase_.u ? startTwist_.at(y)
                                  : pose.u == endPhase_.u ? endTwist_.at(y)
                                                          : law_.velocity(pose.phase, y);
            c.speed = glm::dot(n, velocity);
            c.bend = bendAt(height, off);
            return c;
        };
        // Whether, where the line's end on that side grows at pose a and shrinks at pose b, the
        // pose between them where it stops growing bounds the points beyond its interval over
        // the whole node (note l); the poses tried go into O.
        const auto graze = [&](std::size_t p, int upper, Solved& a, Solved& b, double& end) {
            if (a.range.isEmpty() || b.range.isEmpty()) return false;
            const Crossing& ca = crossing(a, p, upper);
            const Crossing& cb = crossing(b, p, upper);
            if (!(ca.speed > 0.0 && cb.speed < 0.0)) return false;
            // Only where (j)'s bound from a pose in the node's middle, C (w / 2)^2, would hold.
            const double width = b.u - a.u;
            if (!(std::max(ca.bend, cb.bend) * width * width < 4.0 * epsilon_)) return false;
            bool settled = false;
            regulaFalsi(a.u, b.u, ca.speed, cb.speed, kGrazeSteps, [&](double u) -> std::optional<double> {
                const TurnPhase phase = law_.phase(u);
                Solved g{u, law_.pose(phase), Interval::empty(), {}, phase};
                g.range = tool_.intersectPart(parts[p], LocalLine::make(g.pose, line));
                if (g.range.isEmpty()) return std::nullopt;
                found.add(g.range, u, p);
                const Crossing& c = crossing(g, p, upper);
                const double out = upper ? c.across : -c.across;
                const double back = u - a.u, on = b.u - u;
                settled = out > 0.0 && out >= axisTurn_ * std::max(back, on) &&
                          -back * c.speed + back * back * c.bend < epsilon_ && on * c.speed + on * on * c.bend < epsilon_;
                if (settled) {
                    end = upper ? g.range.hi : g.range.lo;
                    return std::nullopt;
                }
                return c.speed;
            });
            return settled;
        };
        // Whether, where the line's crossings at poses a and b lie on two faces that meet at a
        // rim, the pose between them where the line passes through that rim bounds the points
        // beyond its interval over the whole node (note k); the pose goes into O.
        const auto corner = [&](std::size_t p, int upper, Solved& a, Solved& b, double& end) {
            if (a.range.isEmpty() || b.range.isEmpty()) return false;
            const int fa = crossing(a, p, upper).face, fb = crossing(b, p, upper).face;
            if (std::abs(fa - fb) != 1) return false;
            const std::optional<Rim> r = rim(p, std::min(fa, fb));
            if (!r) return false;
            // g(u): how far outside the rim's radius the line crosses the rim's plane at pose u.
            const auto g = [&](double u) {
                const ToolPose ps = law_.pose(u);
                const double along = glm::dot(ps.axis, line.dir);
                const double t = (r->z - glm::dot(ps.axis, line.origin - ps.tip)) / along;
                return glm::length(line.at(t) - ps.tip - r->z * ps.axis) - r->radius;
            };
            const double ga = g(a.u), gb = g(b.u);
            if (!std::isfinite(ga) || !std::isfinite(gb) || (ga > 0.0) == (gb > 0.0)) return false;
            double u = a.u;
            regulaFalsi(a.u, b.u, ga, gb, kCornerSteps, [&](double next) -> std::optional<double> {
                u = next;
                const double gu = g(u);
                if (!std::isfinite(gu) || std::abs(gu) <= kCornerGap) return std::nullopt;
                return gu;
            });
            const TurnPhase phase = law_.phase(u);
            const ToolPose ps = law_.pose(phase);
            const Interval range = tool_.intersectPart(parts[p], LocalLine::make(ps, line));
            if (range.isEmpty()) return false;
            found.add(range, u, p);
            // The end, and the rim's point nearest it: both faces' planes through that point hold
            // the part, and the end lies `gap` from it.
            const Vec3 y = line.at(upper ? range.hi : range.lo);
            const Vec3 offAxis = y - ps.tip - glm::dot(y - ps.tip, ps.axis) * ps.axis;
            const double rho = glm::length(offAxis);
            if (!(rho > 0.0)) return false;
            const Vec3 radial = offAxis / rho, point = ps.tip + r->z * ps.axis + r->radius * radial;
            const double gap = glm::length(y - point), bend = bendAt(r->z, r->radius);
            const Vec3 velocity = law_.velocity(phase, point);
            // Back over [a.u, u] (sign -1) and on over [u, b.u] (sign 1), each by either face.
            for (const double sign : {-1.0, 1.0}) {
                const double w = sign < 0.0 ? u - a.u : b.u - u;
                bool bounded = false;
                for (int f = 0; f < 2 && !bounded; ++f) {
                    const Vec3 n = r->across[f] * radial + r->along[f] * ps.axis;
                    const double out = upper ? glm::dot(n, line.dir) : -glm::dot(n, line.dir);
                    bounded = out > 0.0 && out >= axisTurn_ * w && gap < epsilon_ &&
                              sign * w * glm::dot(n, velocity) + w * w * bend + gap * (1.0 + axisTurn_ * w) < epsilon_;
                }
                if (!bounded) return false;
            }
            end = upper ? range.hi : range.lo;
            return true;
        };
        // Whether, where the line's end on that side lies on the same disk or cylinder face at
        // poses a and b, that face bounds the points beyond the farthest end of a, b and (where
        // the end dips past theirs) a pose solved between them, over the whole node (note o); that
        // pose goes into O.
        const auto faceDip = [&](std::size_t p, int upper, Solved& a, Solved& b, double& end) {
            if (!std::isfinite(axisJerk_) || a.range.isEmpty() || b.range.isEmpty()) return false;
            const Crossing& ca = crossing(a, p, upper);
            const Crossing& cb = crossing(b, p, upper);
            if (ca.face != cb.face) return false;
            // The first and last faces up the meridian are the bottom and top disks (meridianFaces).
            const std::vector<MeridianFace>& faces = faces_[p];
            const MeridianFace& face = faces[std::size_t(ca.face)];
            const bool disk = ca.face == 0 || ca.face == int(faces.size()) - 1;
            if (!disk && !(face.kind == MeridianFace::Kind::Cone && face.r0 == face.r1)) return false;
            const double w = b.u - a.u, turn = axisTurn_, bend = axisBend_, feed = tipSpeed_;
            const double out = upper ? std::min(ca.across, cb.across) : -std::max(ca.across, cb.across);
            if (disk && !(out > 0.5 * turn * w)) return false;
            const double side = ca.face == 0 ? -1.0 : 1.0, radius = face.r0;
            const Vec3 beyond = upper ? line.dir : -line.dir;
            // F_z at a pose: a disk's H_z, or a cylinder's G_z; positive outside.
            const auto F = [&](const ToolPose& pose, const Vec3& z) {
                const Vec3 q = z - pose.tip;
                const double along = glm::dot(pose.axis, q);
                return disk ? side * (along - face.z0) : glm::dot(q, q) - along * along - radius * radius;
            };
            // How far below 0 F_z may fall at a point no deeper than epsilon.
            const double depth = disk ? epsilon_ : epsilon_ * (2.0 * radius - epsilon_);
            const auto endOf = [&](const Interval& range) { return upper ? range.hi : range.lo; };
            const auto farther = [&](double s, double t) { return upper ? std::max(s, t) : std::min(s, t); };
            // Whether the points beyond line.at(t) lie outside every T(u) of the node but for
            // epsilon, by P through F_z at a, the pose `mid` at u and b, less the remainder;
            // `low` gets where P is least.
            const auto holds = [&](double t, double u, const ToolPose& mid, double& low) {
                const Vec3 z = line.at(t);
                const double reach = std::max(glm::length(z - a.pose.tip), glm::length(z - b.pose.tip));
                if (!disk) {
                    // Beyond z a cylinder's G grows where the line runs away from the axis,
                    // g(u) = (z - p).e - (a.(z - p))(a.e) >= 0 (e the direction beyond), and
                    // |g'| <= 2 (|f| + omega |z - p|): each u lies within w / 2 of a or b.
                    const auto g = [&](const ToolPose& pose) {
                        const Vec3 q = z - pose.tip;
                        return glm::dot(q, beyond) - glm::dot(pose.axis, q) * glm::dot(pose.axis, beyond);
                    };
                    if (!(std::min(g(a.pose), g(b.pose)) > (feed + turn * reach) * w)) return false;
                }
                const double jerk = axisJerk_ * reach + 3.0 * bend * feed;
                const double bound = disk ? jerk
                                          : 2.0 * reach * jerk + 6.0 * (turn * reach + feed) * (bend * reach + 2.0 * turn * feed);
                const ParabolaLow p2 = parabolaLow(a.u, F(a.pose, z), u, F(mid, z), b.u, F(b.pose, z));
                low = p2.u;
                return p2.value - bound * nodePolynomialMax(a.u, u, b.u) / 6.0 > -depth;
            };
            double t = farther(endOf(a.range), endOf(b.range)), deepest = 0.0;
            // The root's middle pose is kept (midPose_): most lines that reach here are the root's.
            const double um = 0.5 * (a.u + b.u);
            if (holds(t, um, um == midPhase_.u ? midPose_ : law_.pose(um), deepest)) {
                end = t;
                return true;
            }
            if (!(deepest > a.u && deepest < b.u)) return false;
            const ToolPose pose = law_.pose(deepest);
            const Interval range = tool_.intersectPart(parts[p], LocalLine::make(pose, line));
            if (range.isEmpty()) return false;
            found.add(range, deepest, p);
            t = farther(t, endOf(range));
            double unused = 0.0;
            if (!holds(t, deepest, pose, unused)) return false;
            end = t;
            return true;
        };
        // Whether a node of width w that is not settled as a linear node has the line's points
        // beyond its end poses' intervals (a, b) bounded by those poses' faces (note j), `swept`
        // holding every point of the node deeper than epsilon; `aim` lets notes k and l solve
        // poses to that end.
        const auto anchoredSettled = [&](std::size_t p, double w, std::uint32_t a, std::uint32_t b,
                                         const Interval& swept, bool aim) {
            Solved* const ends[2] = {&solved[a], &solved[b]};
            const Interval hull = ends[0]->range.hull(ends[1]->range);
            if (hull.isEmpty()) return false;
            // How far into the node, from end e, the crossing at end `upper` of that pose's
            // interval bounds the points on the line beyond `cut`: the stretch tau_e below which
            // (j)'s bound holds, with the distance D from the crossing to `cut` as slack (note m).
            // The model moves on from pose a (sign 1) and back from pose b.
            const auto stretch = [&](int e, int upper, double cut) {
                if (ends[e]->range.isEmpty()) return 0.0;
                const Crossing& c = crossing(*ends[e], p, upper);
                const double out = upper ? c.across : -c.across;
                if (!(out > 0.0)) return 0.0;
                const double slack = upper ? cut - ends[e]->range.hi : ends[e]->range.lo - cut;
                const double sign = e == 0 ? 1.0 : -1.0;
                const double A = epsilon_ + slack * out, B = slack * axisTurn_ + sign * c.speed;
                // The positive root of A - B tau - C tau^2, in the form without cancellation.
                const double disc = std::sqrt(B * B + 4.0 * c.bend * A);
                const double root = B >= 0.0 ? 2.0 * A / (B + disc)
                                    : c.bend > 0.0 ? (disc - B) / (2.0 * c.bend)
                                                   : std::numeric_limits<double>::infinity();
                return axisTurn_ > 0.0 ? std::min(root, out / axisTurn_) : root;
            };
            // Only a side whose stretch beyond both poses' intervals O leaves open needs a bound;
            // where only the stretch between them is open, either pose may close it.
            const bool loOpen = !held({swept.lo, std::min(hull.lo, swept.hi)});
            const bool hiOpen = !held({std::max(hull.hi, swept.lo), swept.hi});
            const bool between = !loOpen && !hiOpen;
            Interval cut = swept;
            bool bounded = false;
            for (const int upper : {1, 0}) {
                if (!(upper ? hiOpen : loOpen) && !between) continue;
                // The pose whose end is the farther is tried first: where the end moves outward
                // from one pose to the other, the face at the nearer advances towards the farther's
                // end, and only the farther's crossing can bound the node alone (on
                // BM_TurningShortQuery's flat end, the nearer did so on 56 sides in 45,682, the
                // farther on 38,148), so the nearer's crossing is found only where that fails.
                const int farther = upper ? (ends[0]->range.hi > ends[1]->range.hi ? 0 : 1)
                                          : (ends[0]->range.lo < ends[1]->range.lo ? 0 : 1);
                // Where the line's points beyond some parameter are bounded: beyond a pose's own
                // end where its crossing bounds the whole node (j: D = 0, tau_e > w), beyond the
                // farther end where the two poses share it (m), or beyond the end of a pose solved
                // at a rim or a graze between them (k, l).
                const auto endOf = [&](int e) { return upper ? ends[e]->range.hi : ends[e]->range.lo; };
                std::optional<double> end;
                for (const int e : {farther, 1 - farther})
                    if (!end && stretch(e, upper, endOf(e)) > w) end = endOf(e);
                const double beyond = upper ? hull.hi : hull.lo;
                if (!end && stretch(0, upper, beyond) + stretch(1, upper, beyond) > w) end = beyond;
                double aimed = 0.0;
                if (!end && !between && faceDip(p, upper, *ends[0], *ends[1], aimed)) end = aimed;
                if (!end && !between && aim &&
                    (corner(p, upper, *ends[0], *ends[1], aimed) || graze(p, upper, *ends[0], *ends[1], aimed)))
                    end = aimed;
                if (!end) {
                    if (!between) return false;
                    continue;
                }
                if (upper) {
                    cut.hi = std::min(cut.hi, *end);
                } else {
                    cut.lo = std::max(cut.lo, *end);
                }
                bounded = true;
            }
            if (!bounded) return false;
            return held(cut);
        };
        // A node's grown band swept along its move, along the line: empty where it misses the
        // care. Four in ten of the nodes' sweeps miss the line (BM_TurningQuery, BM_TurningShortQuery),
        // most of them beside the band or above or below it, which the narrowed bound tells for a
        // fifth of the sweep's cost (the ball end's short rows 53 -> 37 ns a line).
        const auto sweptWithin = [&](const MoveSweep& sweep) {
            return sweep.narrowBound(line, within).isEmpty() ? Interval::empty() : sweep.intersect(line);
        };
        // Whether the end poses' faces left the part's root open (note n).
        bool rootOpen = false;
        for (std::size_t b = 0; b < models_.size(); ++b) {
            const std::size_t p = models_[b].part;
            if (b == 0 || models_[b - 1].part != p) {
                // The part's root, taken whole, settles all its bands at once: by its end poses'
                // faces (note n) where no ball's capsules come first, else by its sweep.
                bool settled = false;
                if (parts.size() == 1 && balls_.empty()) {
                    addEnds(p);
                    settled = anchoredSettled(p, 1.0, 0, 1, Interval::all(), false);
                    rootOpen = !settled;
                }
                if (!settled && wholeRoots_[p]) {
                    const Interval swept = sweptWithin(wholeRoots_[p]->sweep);
                    if (!held(swept) && endsAdded != p) addEnds(p);
                    settled = held(swept);
                }
                if (settled) {
                    while (b + 1 < models_.size() && models_[b + 1].part == p) ++b;
                    continue;
                }
            }
            const int leaf = models_[b].leafLevel();
            if (solved.size() > 2) solved.resize(2);
            // A node pops itself and pushes its two halves: at most one node a level and two of
            // the deepest. Each carries its end poses' indices into `solved`.
            struct Node {
                std::uint32_t heap, a, b;
            };
            std::array<Node, kMaxLinearLevel + 2> stack;
            std::size_t top = 0;
            std::unique_ptr<LinearNode> scratch;  // a node made for this query alone
            stack[top++] = {1, 0, 1};
            while (top > 0) {
                const Node n = stack[--top];
                // Below the root, where the end poses' faces settle the node within the line's
                // bound, its sweep is not needed (note n).
                if (n.heap > 1 && parts.size() == 1 &&
                    anchoredSettled(p, heapWidth(n.heap), n.a, n.b, Interval::all(), false))
                    continue;
                // A part searched whole (one band) whose end poses' faces left its root open: the
                // root's grown sweep settles few of those lines (on BM_TurningShortQuery's flat end
                // at 0.2 degrees, one in eighteen, and its aimed test of notes k and l one in four),
                // so the root is split at once, its halves tried by note n before their sweeps.
                const bool splitRoot = n.heap == 1 && rootOpen && !wholeRoots_[p] && leaf > 0;
                const LinearNode* node = nullptr;
                if (!splitRoot) {
                    node = &linearNode(b, n.heap, scratch);
                    const Interval swept = sweptWithin(node->sweep);
                    if (heapLevel(n.heap) == leaf) {  // closed: the band's own sweep along the node's move
                        if (!swept.isEmpty()) found.add(swept, node->middleU, node->middleU, b, n.heap);
                        continue;
                    }
                    if (held(swept)) continue;  // settled: the grown band's sweep is held
                    if (n.heap == 1 && endsAdded != p) {
                        addEnds(p);
                        if (held(swept)) continue;
                    }
                    if (parts.size() == 1 && anchoredSettled(p, node->width, n.a, n.b, swept, true)) continue;
                }
                const double middleU = node ? node->middleU : midPhase_.u;
                const ToolPose& middlePose = node ? node->middle : midPose_;
                const Interval middle = tool_.intersectPart(parts[p], LocalLine::make(middlePose, line));
                if (!middle.isEmpty()) found.add(middle, middleU, p);
                const std::uint32_t m = std::uint32_t(solved.size());
                solved.push_back({middleU, middlePose, middle, {}, node ? node->phase : midPhase_});
                stack[top++] = {2 * n.heap + 1, m, n.b};
                stack[top++] = {2 * n.heap, n.a, m};
            }
        }
    } else {
        // The poses solved, each with its line in the tool's frame and its phase; nodes refer to
        // them by index. Pose e's interval in part p is exact[e * parts.size() + p].
        struct End {
            LocalLine local;
            TurnPhase phase;
        };
        std::vector<End> ends;
        std::vector<Interval> exact;
        ends.reserve(64);
        exact.reserve(64 * parts.size());
        auto solve = [&](const TurnPhase& phase, const ToolPose& pose) {
            const LocalLine local = LocalLine::make(pose, line);
            for (std::size_t p = 0; p < parts.size(); ++p) {
                const Interval iv = tool_.intersectPart(parts[p], local);
                if (!iv.isEmpty()) found.add(iv, phase.u, p);
                exact.push_back(iv);
            }
            ends.push_back({local, phase});
            return std::uint32_t(ends.size() - 1);
        };
        // Whether the tool at end pose e, grown by level k's reach, holds no point of care outside O
        // (tested piece by piece, on intervals that hold each piece's; each part's own interval at
        // that pose is the root finding's hint).
        auto settled = [&](std::uint32_t e, int k) {
            const std::vector<OuterPart>& level = grown_[std::size_t(k)];
            for (std::size_t p = 0; p < level.size(); ++p)
                if (!allPiecesHeld(level[p], ends[e].local, held, exact[e * parts.size() + p])) return false;
            return true;
        };

        struct Node {
            int level;
            std::uint32_t a, b;  ///< the ends' indices into `ends`
            bool aSettled;       ///< the end at a passed this level's test (as its left sibling's end)
        };
        // A node of level k < levels pops itself and pushes two of level k + 1, so the stack holds
        // at most one node per level and two of the deepest: kMaxLevel + 2 in all.
        const int levels = int(grown_.size());
        std::array<Node, kMaxLevel + 2> stack;
        std::size_t top = 0;
        const std::uint32_t first = solve(startPhase_, startPose_);
        stack[top++] = {0, first, solve(endPhase_, endPose_), false};
        while (top > 0) {
            const Node n = stack[--top];
            if (n.level >= levels) continue;  // a leaf: its reach is at most epsilon
            const std::size_t k = std::size_t(n.level);
            if ((n.aSettled || settled(n.a, n.level)) && settled(n.b, n.level)) {
                // The right sibling, still on the stack, starts at this node's end.
                if (top > 0 && stack[top - 1].level == n.level && stack[top - 1].a == n.b) stack[top - 1].aSettled = true;
                continue;
            }
            if (n.level >= closingLevel_) {  // closed: grown by at most epsilon
                for (std::size_t p = 0; p < parts.size(); ++p)
                    for (const std::uint32_t e : {n.a, n.b}) {
                        const Interval g = intersectPieces(grown_[k][p].pieces, ends[e].local);
                        if (!g.isEmpty()) found.add(g, ends[e].phase.u, p);
                    }
                continue;
            }
            // The middle pose, stepped from the start's phase: within kPhaseStepError per level and
            // turn of the exact pose (1.6e-10 mm at most, well inside epsilon), see note c.
            const TurnPhase middle = law_.advance(ends[n.a].phase, halfSteps_[k]);
            const std::uint32_t m = solve(middle, law_.pose(middle));
            stack[top++] = {n.level + 1, m, n.b, false};
            stack[top++] = {n.level + 1, n.a, m, false};
        }
    }

    // Close the gaps that lie within epsilon of the poses on both sides (d): where the line runs
    // nearly tangent to the envelope, consecutive poses' intervals leave slivers of 1e-7 mm that
    // the continuous motion sweeps, and that a stock must not keep.
    ShortList<Piece> pieces;
    for (const Piece& p : found.pieces()) {
        if (!pieces.empty() && pieces.back().nodeHi == 0 && p.nodeLo == 0) {
            Piece& last = pieces.back();
            const Interval left = intersectPieces(grownEpsilon_[last.partHi], LocalLine::make(pose(last.uHi), line));
            const Interval right = intersectPieces(grownEpsilon_[p.partLo], LocalLine::make(pose(p.uLo), line));
            if (left.hi >= right.lo) {
                last.range.hi = p.range.hi, last.uHi = p.uHi, last.partHi = p.partHi, last.nodeHi = p.nodeHi;
                continue;
            }
        }
        pieces.push_back(p);
    }
    // The Hermite data only for the ends within care: an end outside it meets no material, so no
    // segment end takes its normal (as MoveSweep::EndFilter spares the cutting loop's fixed-axis
    // sweeps). An end a leaf made takes its node's; any other, its pose's.
    const auto hermite = [&](double t, double u, std::size_t part, std::uint32_t node, bool upper, Vec3& normal,
                             bool& sharp) {
        if (!care.empty() &&
            std::none_of(care.begin(), care.end(), [t](const Interval& c) { return c.lo <= t && t <= c.hi; }))
            return;
        if (node != 0) {
            nodeEndNormal(line, t, part, node, upper, normal, sharp);
        } else {
            endNormal(line, t, u, part, normal, sharp);
        }
    };
    out.reserve(pieces.size());
    for (const Piece& p : pieces) {
        LineHit hit;
        hit.range = p.range;
        hermite(p.range.lo, p.uLo, p.partLo, p.nodeLo, false, hit.normalLo, hit.sharpLo);
        hermite(p.range.hi, p.uHi, p.partHi, p.nodeHi, true, hit.normalHi, hit.sharpHi);
        out.push_back(hit);
    }
}

std::vector<Interval> TurningSweep::intersectAll(const Line& line) const {
    std::vector<Interval> out;
    for (const LineHit& h : intersect(line)) out.push_back(h.range);
    return out;
}

}  // namespace dexelmill
