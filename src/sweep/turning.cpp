#include "dexelmill/sweep/turning.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>

#include "dexelmill/error.h"
#include "dexelmill/tool/offset.h"
#include "turning_levels.h"
#include "turning_linear_search.h"
#include "turning_union.h"

namespace dexelmill {

using turning::kMaxLevel;

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

/// Most chords a ball's centre path is cut into; a move that needs more is searched whole.
constexpr double kMaxChords = 256.0;

/// Chords a ball's group holds: a line is tested against a group's ball before its capsules.
constexpr int kChordGroup = 8;

/// TurningSweep::setEndNormalsFromSearch's setting.
std::atomic<bool> endNormalsFromSearch{true};

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

}  // namespace

TurningSweep::TurningSweep(const Tool& tool, const Move& move, double epsilon)
    : tool_(tool), law_(move), epsilon_(epsilon) {
    if (!(epsilon >= kMinTurnTolerance) || !std::isfinite(epsilon)) {
        char text[200];
        std::snprintf(text, sizeof text, "the tolerance of a turning move's sweep must be at least %g mm, not %g",
                      kMinTurnTolerance, epsilon);
        throw Error(text);
    }
    bounds_ = turningMoveBox(move, ToolReach(tool)).padded(kBoxSlack);
    // Every tool point lies within hypot(total length, max radius) of the tip (note a).
    axisTurn_ = law_.axisTurnBound();
    tipSpeed_ = law_.speedBound(0.0);
    axisBend_ = law_.axisBendBound();
    pivotBend_ = law_.axisPointAccelerationBound(0.0);
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
    for (Ball& ball : balls_) {
        for (int j = 0; j <= chords_; ++j) {
            const ToolPose p = law_.pose(double(j) / chords_);
            ball.centres.push_back(p.tip + ball.zc * p.axis);
        }
        // A capsule's points lie within rho of its chord, whose points lie within the farthest
        // of its two ends from any centre (a ball is convex).
        for (int first = 0; first < chords_; first += kChordGroup) {
            const int last = std::min(chords_, first + kChordGroup);
            Box box;
            for (int j = first; j <= last; ++j) box.expand(ball.centres[std::size_t(j)]);
            Ball::Group g;
            g.centre = 0.5 * (box.lo + box.hi);
            for (int j = first; j <= last; ++j)
                g.radius = std::max(g.radius, glm::length(ball.centres[std::size_t(j)] - g.centre));
            g.radius += ball.rho + kBoxSlack;
            ball.groups.push_back(g);
        }
        for (int j = 0; j < chords_; ++j)
            ball.capsuleReach = std::max(ball.capsuleReach, 0.5 * glm::length(ball.centres[std::size_t(j) + 1] -
                                                                             ball.centres[std::size_t(j)]));
        ball.capsuleReach += ball.rho + kBoxSlack;
    }
    for (const ConvexPart& part : parts_) {
        grownEpsilon_.push_back(offsetPart(tool_, part, epsilon_));
        faces_.push_back(meridianFaces(tool_.pieces(), part));
    }
    markCoveredDisks(faces_, parts_, !balls_.empty());
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
    // The static search closes its nodes from the first level whose growth is at most epsilon,
    // which must come by kMaxLevel. Readers keep positions within 1e9 mm and a move's turns
    // within ten, so that a tool point travels at most about 6e10 mm: level 50 at the default
    // tolerance.
    if (!(std::ldexp(speed_, -(kMaxLevel + 1)) <= 2.0 * epsilon_)) {
        char text[200];
        std::snprintf(text, sizeof text,
                      "a turning move whose tool points travel up to %g mm is beyond what its sweep resolves to "
                      "%g mm",
                      speed_, epsilon_);
        throw Error(text);
    }
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
//      itself comes near the line. A move that would need more than kMaxChords chords is searched
//      whole. A line is tested against runs of kChordGroup capsules behind a ball that holds them
//      (their chords' ends lie within its radius less R of its centre), and one that misses the
//      ball, or meets it only outside the care, skips them.
//  (h) Linear nodes. The law bounds how fast the pivot's velocity turns: by the axis's turn
//      alone where the tip runs on a straight line (an APT MULTAX move, or a machine's move under
//      tool centre point control), and turn by turn down the heads' and the tables' chains in
//      identity kinematics, where the machine carries the tip on a curve. The tip's travel |f| is
//      most of V on a typical move, and the search above pays for it at every level. A node can instead be taken as a fixed-axis
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
//      (mitredOffsetPart, a superset; its tori as chains of cones, kChainSlack) swept along its
//      move holds no point of care outside O;
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
//  (j)-(q) The tests that settle a linear node by the faces of its end poses, the bands a line
//      cannot reach and the gaps between a node's poses: in turning_linear_search.cpp, with the
//      search over linear nodes (TurningSweep::LinearSearch).
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
    turning::Union found;
    const turning::Care matters(careBegin, careEnd, found);
    // Every output interval lies within the parts' grown sweeps (outer_, bound()), so a line
    // whose care misses their narrowed bounds has none: one that passes a box of theirs beside
    // the tool, in a corner. On BM_TurningShortQuery that is a third of the lines the cutting
    // loop asks about, each of which solved both end poses and the root's sweep to find nothing
    // (bull nose 294 -> 260 ns a line, flat end 116 -> 112). A ball's capsules (g) turn such
    // lines away for about what the test costs, so a ball end skips it.
    if (!outer_.empty() && balls_.empty()) {
        Interval near;
        for (const MoveSweep& part : outer_) near = near.hull(part.narrowBound(line, matters.within()));
        if (!matters.meets(near)) return;
    }

    const auto& parts = parts_;
    // The balls' capsules (g); each end's pose is where its chord comes nearest it.
    // A group's chords are tested only where its ball meets the line within the care's hull.
    // Consecutive capsules' intervals overlap on most lines that meet them (four in a row on
    // BM_TurningQuery's ball end at 30 degrees), so each run of them goes into O at once, its
    // ends taken from the capsules a sequence of adds would take them from (the later on a tie).
    for (std::size_t b = 0; b < balls_.size(); ++b) {
        const std::vector<Vec3>& c = balls_[b].centres;
        const auto chordU = [&](int j, double t) {
            const Vec3 m = c[std::size_t(j) + 1] - c[std::size_t(j)];
            const double mm = glm::dot(m, m);
            const double s = mm > 0.0 ? std::clamp(glm::dot(line.at(t) - c[std::size_t(j)], m) / mm, 0.0, 1.0) : 0.0;
            return (j + s) / chords_;
        };
        Interval run = Interval::empty();
        int jLo = 0, jHi = 0;  // the chords whose capsules made the run's ends
        const auto flush = [&] {
            if (!run.isEmpty()) found.add(run, chordU(jLo, run.lo), chordU(jHi, run.hi), parts.size() + b);
        };
        for (int j = 0; j < chords_; ++j) {
            if (j % kChordGroup == 0) {
                const Ball::Group& g = balls_[b].groups[std::size_t(j / kChordGroup)];
                const Vec3 oc = g.centre - line.origin;
                const double t = glm::dot(oc, line.dir);
                if (glm::dot(oc, oc) - t * t > g.radius * g.radius ||
                    !matters.meets({t - g.radius, t + g.radius})) {
                    j += kChordGroup - 1;
                    continue;
                }
            }
            // And each capsule behind the ball about its chord's middle.
            const Vec3 om = 0.5 * (c[std::size_t(j)] + c[std::size_t(j) + 1]) - line.origin;
            const double tm = glm::dot(om, line.dir), reach = balls_[b].capsuleReach;
            if (glm::dot(om, om) - tm * tm > reach * reach) continue;
            const Interval iv = lineCapsule(line, c[std::size_t(j)], c[std::size_t(j) + 1], balls_[b].rho);
            if (iv.isEmpty()) continue;
            if (run.isEmpty() || iv.lo > run.hi || iv.hi < run.lo) {
                flush();
                run = iv, jLo = jHi = j;
                continue;
            }
            if (iv.lo <= run.lo) run.lo = iv.lo, jLo = j;
            if (iv.hi >= run.hi) run.hi = iv.hi, jHi = j;
        }
        flush();
    }
    // The search also keeps what it found of the end poses' faces for the Hermite data below
    // (setEndNormalsFromSearch).
    LinearSearch search(*this, line, matters, found);
    if (!models_.empty()) {
        search.run();
    } else {
        const auto held = [&](const Interval& g) { return matters.held(g); };
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
    turning::ShortList<turning::Piece> pieces;
    for (const turning::Piece& p : found.pieces()) {
        if (!pieces.empty() && pieces.back().nodeHi == 0 && p.nodeLo == 0) {
            turning::Piece& last = pieces.back();
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
        } else if (!endNormalsFromSearch.load(std::memory_order_relaxed) ||
                   !search.knownEndNormal(t, u, part, normal, sharp)) {
            endNormal(line, t, u, part, upper, normal, sharp);
        }
    };
    out.reserve(pieces.size());
    for (const turning::Piece& p : pieces) {
        LineHit hit;
        hit.range = p.range;
        hermite(p.range.lo, p.uLo, p.partLo, p.nodeLo, false, hit.normalLo, hit.sharpLo);
        hermite(p.range.hi, p.uHi, p.partHi, p.nodeHi, true, hit.normalHi, hit.sharpHi);
        out.push_back(hit);
    }
}

void TurningSweep::setEndNormalsFromSearch(bool fromSearch) {
    endNormalsFromSearch.store(fromSearch, std::memory_order_relaxed);
}

std::vector<Interval> TurningSweep::intersectAll(const Line& line) const {
    std::vector<Interval> out;
    for (const LineHit& h : intersect(line)) out.push_back(h.range);
    return out;
}

}  // namespace dexelmill
