// One line's search over a turning sweep's linear nodes (notes h and i of turning.cpp), and the
// tests that settle a node by the faces of its end poses (notes j to o below), the bands a line
// cannot reach (note p, at reaches) and the gaps between a node's poses (note q).
#include "turning_linear_search.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

#include "dexelmill/geometry/roots.h"
#include "interpolation.h"
#include "turning_levels.h"

namespace dexelmill {

using turning::heapLevel;
using turning::heapWidth;
using turning::kMaxLinearLevel;
using turning::nodePolynomialMax;
using turning::ParabolaLow;
using turning::parabolaLow;

namespace {

/// Most poses note k solves for where a line passes through a rim (Newton's method), and how near
/// the rim's radius (mm) the line's crossing of its plane must come to stop sooner.
constexpr int kCornerSteps = 12;
constexpr double kCornerGap = 1e-9;

/// Most regula falsi steps note l takes towards the pose where a line's end stops growing, and
/// most poses it then solves to cover the node. Most nodes are covered after the first step: from
/// 2 to 5 steps, and from 2 to 8 poses after them, the bull nose's rows stay within 2 %.
constexpr int kGrazeSteps = 3;
constexpr int kCoverSteps = 4;

/// Most poses a node's gaps are bridged with (TurningSweep::LinearSearch::bridge).
constexpr int kBridgeSteps = 4;

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

// Method, continued from TurningSweep::intersect (turning.cpp, notes a to i).
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
//      from +-tau a(e) x a'(e) by at most |a''| tau^2 / 2 (|a''| <= MotionLaw::axisBendBound)
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
//      opposite signs at the ends, and Newton's method kept inside that bracket (newtonBracket)
//      brings it within kCornerGap of zero, on the side where the line meets the part, in at
//      most kCornerSteps poses. The pose u_c there is solved and goes into O; where the steps
//      reached the rim it serves every node of the line's search that holds it, as what follows
//      asks only that it be such a pose.
//      Where one end pose's part misses the line and the other's end grows towards it, the line
//      may first (or last) meet the part at a rim: g > 0 at the pose that misses (a line crossing
//      the rim's plane inside the rim would meet the part), and the rims tried are those of the
//      face the other pose's crossing lies on. Let y be u_c's end on that side and r the rim's
//      point nearest y, gap = |y - r|. Every plane through r whose normal n lies in the rim's
//      normal cone (n = alpha n_k + beta n_k+1, alpha, beta >= 0, the faces' normals there) holds
//      the part: each face's, and where the line crosses one face's plane inward and the other's
//      outward, the one along the line (n.d = 0). So (j)'s argument holds with r in place of y:
//      for z = y + s d beyond y, with out = n.d taken towards the beyond, s out <= n.(z - r) + gap
//      and |z - r| <= s + gap, so
//        s (out - omega tau) <= -epsilon + gap (1 + omega tau) +- tau n.v + C tau^2,
//      with v the velocity of the tool point at r and C (j)'s bound at r's height and radius. The
//      points beyond y that matter lie within S of it (the care's hull, and the node's grown sweep
//      where it is made), so the left side is at least min(0, S (out - omega tau)), concave in
//      tau, and the right side is convex: where it is below that at tau = 0 (gap < epsilon when
//      out >= 0) and at tau = w, no point beyond y is deeper than epsilon in any T(u) with
//      |u - u_c| <= w on that side of u_c. (Taking S infinite asks out >= omega w, as (j) does.)
//      The node is settled on that side when one plane does so back to its start (the sign -)
//      and one, the same or another, on to its end (+), and its grown sweep cut at y is held, its
//      gaps bridged as (q) says.
//      Cost: past the kink each face's normal speed keeps its sign, so each bounds a wide node
//      at first order; a z-line meeting a flat end's bottom rim settles at the node whose end
//      poses straddle the kink, a few Newton steps of a pose and a few dot products each.
//      A line the bottom rim first meets at its corner, entering the bottom face and leaving the
//      side at once, is bounded back to where the part misses it by the plane along the line,
//      which recedes there: on BM_TurningQuery's flat end at 1 degree such first contacts made a
//      quarter of its z lines descend to the leaves, and with (q) they settle at the node where
//      the rim is first found (the flat end's long rows 0.68-0.81 of before, its short rows
//      0.86-0.92).
//  (l) Grazes. Where the end on one side grows at pose a (n.v > 0 at its crossing, in (j)'s
//      sense) and shrinks at b (n.v < 0), it stops growing at a pose between them, where n.v = 0
//      and (j)'s bound is of second order: a pose there bounds about sqrt(epsilon / C) of u on
//      either side, and (j) from the node's end poses settles the nodes around it only when one
//      lies that near it (a bull nose on BM_TurningQuery's 32 mm move descends 6 to 7 levels).
//      So where (j) bounds neither side, and the node is narrow enough that (j)'s bound from a
//      pose in its middle could hold (C w^2 < 4 epsilon, C the larger of the two crossings'),
//      regula falsi (Illinois) on n.v, each step a solved pose that goes into O, looks for that
//      pose in at most kGrazeSteps steps, and the node is covered by stretches: (j)'s argument
//      from a pose e inside the node holds for the poses u after e with the sign + and before it
//      with the sign -, and with (m)'s slack for the points beyond H, here the farthest end on
//      that side of a, b and the poses solved (O holds it). So each pose bounds the points
//      beyond H over a stretch of u around it, a on and b back (note m's tau). Once these
//      stretches cover the node, no point beyond H is deeper than epsilon inside any T(u) of it,
//      and the node is settled on that side; where the steps end first, poses in the middle of
//      the first stretch left uncovered are solved, at most kCoverSteps. One pose near the graze
//      bounding the whole node alone, as this test first asked, settled 53 % of the nodes that
//      tried it on BM_TurningQuery's bull nose at 10 degrees (87-90 % at 1 degree), each failure
//      four poses lost; with the end poses' stretches all of them settle, most after the first
//      pose (1.1 poses a node at 10 degrees, 1.7 at 1): its long rows 0.96, 0.79 and 0.86 at 1,
//      10 and 30 degrees, its short rows 1.00 and 0.93 at 0.2 and 0.6. Tried at any width,
//      the test settled wider nodes (the z lines' nodes 13 -> 7 at 1 degree) for about as much
//      on the long rows, and made the short rows 2-5 % slower.
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
//      A node below the root whose two end poses both meet the line takes the tests of (j) to
//      (q) before its sweep, and where they fail is split without it (above the leaves, whose
//      sweep is their answer): such a node's grown sweep reaches past both poses' intervals,
//      and on BM_TurningQuery O held it for about one in a thousand (bull nose) to three in a
//      thousand (flat end). The bull nose's long rows 0.73-0.75 of before, its short rows 0.92,
//      the flat end's long rows 0.93-0.95.
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
//      |a''| (MotionLaw::axisBendBound) and |z - p(u)| largest at an end of the tip's segment.
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
//  (p) Bands a line cannot reach: at TurningSweep::LinearSearch::reaches.
//  (q) Gaps. Where (j) to (o) bound both sides of a node but O leaves a gap in the cut between two
//      of its intervals, whose ends poses u_L and u_R inside the node made, poses between them are
//      solved (bridge): were the intervals to move linearly from u_L's to u_R's, the one whose
//      interval grown by epsilon still reaches the left one, or where some reach both, the middle
//      of those. Its interval goes into O (a static pose's, as every middle pose's does), and its
//      part grown by epsilon within the gap: within epsilon of S (1), and between intervals of O,
//      so that this part moves no end of O. At most
//      kBridgeSteps poses; where they close every gap the node is settled as if O had held the
//      cut, and where not it is split as before, its poses kept. A rim's pose (k) where the line
//      only clips the rim has an interval of near zero length, and the other pose's lies a little
//      beyond it: the dyadic middles took seven levels to close that gap, the grown intervals one
//      or two poses.

TurningSweep::LinearSearch::LinearSearch(const TurningSweep& sweep, const Line& line, const turning::Care& care,
                                         turning::Union& found)
    : s_(sweep), line_(line), care_(care), found_(found), solved_(threadSolved()), endsAdded_(sweep.parts_.size()) {
    solved_.clear();
}

void TurningSweep::LinearSearch::addEnds(std::size_t p) {
    if (!atStart_) atStart_ = LocalLine::make(s_.startPose_, line_), atEnd_ = LocalLine::make(s_.endPose_, line_);
    const Interval first = s_.tool_.intersectPart(s_.parts_[p], *atStart_);
    const Interval last = s_.tool_.intersectPart(s_.parts_[p], *atEnd_);
    if (!first.isEmpty()) found_.add(first, 0.0, p);
    if (!last.isEmpty()) found_.add(last, 1.0, p);
    endsAdded_ = p;
    endFaces_[0][0] = endFaces_[0][1] = endFaces_[1][0] = endFaces_[1][1] = EndFace{};
    solved_.clear();
    solved_.push_back({s_.startPhase_.u, s_.startPose_, first, {}, s_.startPhase_});
    solved_.push_back({s_.endPhase_.u, s_.endPose_, last, {}, s_.endPhase_});
}

double TurningSweep::LinearSearch::bendAt(double height, double off) const {
    const double turn = s_.axisTurn_;
    const double pivotSpeed = s_.tipSpeed_ + turn * std::abs(height);
    return turn * (pivotSpeed + turn * off) +
           0.5 * (s_.pivotBend_ + s_.axisBend_ * std::abs(height) + (s_.axisBend_ + turn * turn) * off);
}

const TurningSweep::LinearSearch::Crossing& TurningSweep::LinearSearch::crossing(Solved& pose, std::size_t p,
                                                                                  int upper) {
    Crossing& c = pose.ends[upper];
    if (c.found) return c;
    const Vec3 y = line_.at(upper ? pose.range.hi : pose.range.lo);
    // At the first and last poses, which make most output ends on a short move, the same look at
    // the faces gives the Hermite data there, where no other face is near (knownEndNormal).
    EndFace* end = nullptr;
    for (std::size_t e = 0; e < 2 && e < solved_.size(); ++e)
        if (&pose == &solved_[e]) end = &endFaces_[e][upper];
    const Vec3 n = s_.faceNormal(pose.pose, p, y, &c.face, end ? &end->alone : nullptr);
    if (end) end->normal = n;
    const double height = glm::dot(y - pose.pose.tip, pose.pose.axis);
    const double off = glm::length(y - pose.pose.tip - height * pose.pose.axis);
    c.found = true;
    c.across = glm::dot(n, line_.dir);
    const Vec3 velocity = pose.u == s_.startPhase_.u ? s_.startTwist_.at(y)
                          : pose.u == s_.endPhase_.u   ? s_.endTwist_.at(y)
                                                       : s_.law_.velocity(pose.phase, y);
    c.speed = glm::dot(n, velocity);
    c.bend = bendAt(height, off);
    return c;
}

double TurningSweep::LinearSearch::stretch(Solved& pose, std::size_t p, int upper, double cut, double sign) {
    if (pose.range.isEmpty()) return 0.0;
    const Crossing& c = crossing(pose, p, upper);
    const double out = upper ? c.across : -c.across;
    // (A speed without a value would make B NaN, and the root below infinite where C = 0.)
    if (!(out > 0.0) || std::isnan(c.speed)) return 0.0;
    const double slack = upper ? cut - pose.range.hi : pose.range.lo - cut;
    const double A = s_.epsilon_ + slack * out, B = slack * s_.axisTurn_ + sign * c.speed;
    // The positive root of A - B tau - C tau^2, in the form without cancellation.
    const double disc = std::sqrt(B * B + 4.0 * c.bend * A);
    const double root = B >= 0.0 ? 2.0 * A / (B + disc)
                        : c.bend > 0.0 ? (disc - B) / (2.0 * c.bend)
                                       : std::numeric_limits<double>::infinity();
    return s_.axisTurn_ > 0.0 ? std::min(root, out / s_.axisTurn_) : root;
}

// Whether, where the line's end on that side grows at pose a and shrinks at pose b, the
// poses found near the one where it stops growing, with a and b, bound the points beyond the
// farthest of their ends over the whole node (note l); the poses go into O.
bool TurningSweep::LinearSearch::graze(std::size_t p, int upper, Solved& a, Solved& b, double& end) {
    if (a.range.isEmpty() || b.range.isEmpty()) return false;
    const Crossing& ca = crossing(a, p, upper);
    const Crossing& cb = crossing(b, p, upper);
    if (!(ca.speed > 0.0 && cb.speed < 0.0)) return false;
    // Only where (j)'s bound from a pose in the node's middle, C (w / 2)^2, would hold.
    const double width = b.u - a.u;
    if (!(std::max(ca.bend, cb.bend) * width * width < 4.0 * s_.epsilon_)) return false;
    turning::ShortList<Solved, kGrazeSteps + kCoverSteps> poses;
    // Whether the stretches of a, b and the poses solved cover the node, each beyond the
    // farthest end of them all (end); else `next`, a pose in the first stretch they leave.
    double next = 0.0;
    const auto covered = [&]() {
        double cut = upper ? std::max(a.range.hi, b.range.hi) : std::min(a.range.lo, b.range.lo);
        for (const Solved& g : poses) cut = upper ? std::max(cut, g.range.hi) : std::min(cut, g.range.lo);
        struct Span {
            double lo, hi;
        };
        turning::ShortList<Span, kGrazeSteps + kCoverSteps + 2> spans;
        spans.push_back(Span{a.u, a.u + stretch(a, p, upper, cut, 1.0)});
        spans.push_back(Span{b.u - stretch(b, p, upper, cut, -1.0), b.u});
        for (Solved& g : poses)
            spans.push_back(Span{g.u - stretch(g, p, upper, cut, -1.0), g.u + stretch(g, p, upper, cut, 1.0)});
        std::sort(spans.begin(), spans.end(), [](const Span& x, const Span& y) { return x.lo < y.lo; });
        double reached = a.u;
        for (const Span& sp : spans) {
            if (sp.lo > reached) break;
            reached = std::max(reached, sp.hi);
        }
        if (reached >= b.u) {
            end = cut;
            return true;
        }
        double to = b.u;
        for (const Span& sp : spans)
            if (sp.lo > reached) to = std::min(to, sp.lo);
        next = 0.5 * (reached + to);
        return false;
    };
    const auto solve = [&](double u) -> Solved* {
        const TurnPhase phase = s_.law_.phase(u);
        Solved g{u, s_.law_.pose(phase), Interval::empty(), {}, phase};
        g.range = s_.tool_.intersectPart(s_.parts_[p], LocalLine::make(g.pose, line_));
        if (g.range.isEmpty()) return nullptr;
        found_.add(g.range, u, p);
        poses.push_back(g);
        return &poses.back();
    };
    bool settled = false;
    regulaFalsi(a.u, b.u, ca.speed, cb.speed, kGrazeSteps, [&](double u) -> std::optional<double> {
        Solved* g = solve(u);
        if (!g || (settled = covered())) return std::nullopt;
        return crossing(*g, p, upper).speed;
    });
    if (settled) return true;
    if (poses.empty()) return false;
    // The last step's cover test set `next`, and no pose has been added since.
    for (int step = 0; step < kCoverSteps; ++step) {
        if (!solve(next)) return false;
        if (covered()) return true;
    }
    return false;
}

// Whether, where the line's crossings at poses a and b lie on two faces that meet at a
// rim, the pose between them where the line passes through that rim bounds the points
// beyond its interval over the whole node (note k); the pose goes into O.
bool TurningSweep::LinearSearch::corner(std::size_t p, int upper, Solved& a, Solved& b, const Interval& swept,
                                        double& end) {
    if (a.range.isEmpty() && b.range.isEmpty()) return false;
    // The rim between the faces the line crosses at a and b; where one pose's part misses the
    // line, a rim of the other's face.
    int lowest = 0, highest = 0;  // the rims tried, faces k and k + 1 for k in [lowest, highest]
    if (a.range.isEmpty() || b.range.isEmpty()) {
        // Only where the end at the other pose grows towards the one that misses: else the end
        // is extreme at that pose, not at a rim the line passes through on the way.
        const Crossing& c = crossing(a.range.isEmpty() ? b : a, p, upper);
        if (a.range.isEmpty() ? c.speed >= 0.0 : c.speed <= 0.0) return false;
        const int f = c.face;
        lowest = f - 1, highest = f;
    } else {
        const int fa = crossing(a, p, upper).face, fb = crossing(b, p, upper).face;
        if (std::abs(fa - fb) != 1) return false;
        lowest = highest = std::min(fa, fb);
    }
    // Where the line crosses a rim's plane at a pose, and that point's offset from the axis.
    const auto rimCrossing = [&](const Rim& rim, const ToolPose& ps, Vec3& x, Vec3& radial) {
        x = line_.at((rim.z - glm::dot(ps.axis, line_.origin - ps.tip)) / glm::dot(ps.axis, line_.dir));
        radial = x - ps.tip - rim.z * ps.axis;
    };
    // g at a pose: how far outside the rim's radius the line crosses the rim's plane.
    const auto gAt = [&](const Rim& rim, const ToolPose& ps) {
        Vec3 x, radial;
        rimCrossing(rim, ps, x, radial);
        return glm::length(radial) - rim.radius;
    };
    std::optional<Rim> r;
    int k = lowest - 1;
    double ga = 0.0, gb = 0.0;
    while (!r && ++k <= highest) {
        r = s_.rim(p, k);
        if (!r) continue;
        ga = gAt(*r, a.pose), gb = gAt(*r, b.pose);
        if (!std::isfinite(ga) || !std::isfinite(gb) || (ga > 0.0) == (gb > 0.0)) r.reset();
    }
    if (!r) return false;
    // The pose where the line passes through the rim: one found for a wider node serves
    // every node that holds it (the bound below asks only that it be such a pose), so a
    // search that descends towards it finds it once.
    const RimPose* at = nullptr;
    for (const RimPose& q : rimPoses_)
        if (q.part == p && q.rim == k && q.u > a.u && q.u < b.u) at = &q;
    RimPose fresh;
    if (!at) {
        // g and its slope. The crossing x stays on the rim's plane {a.(x - p) = z}, so it moves
        // along the line at t' = a.v / a.d, v the velocity of the tool's point at x (with
        // a' = w x a and p' + z a' = v - w x (x - p - z a), w the angular velocity); the radial
        // w_r = x - p - z a changes at d t' - v + w x w_r, and g' = w_r.(d t' - v) / |w_r|.
        // Newton's steps near a simple root tend to stay on one side of it, so they aim at
        // g = -kCornerGap / 2 and stop within kCornerGap / 2 of it: where the line meets the
        // part. (Regula falsi took 6.6 poses a search on BM_TurningQuery's flat end at 1
        // degree, these 4.5: its long rows 0.91-0.95.)
        const double aim = (ga + 0.5 * kCornerGap > 0.0) != (gb + 0.5 * kCornerGap > 0.0) ? 0.5 * kCornerGap : 0.0;
        int poses = 0;
        bool close = false;
        fresh = RimPose{p, k, a.u, a.phase, a.pose, {}};  // the last pose tried
        const auto g = [&](double next, double& gu, double& slope) {
            fresh.u = next;
            fresh.phase = s_.law_.phase(next);
            fresh.pose = s_.law_.pose(fresh.phase);
            Vec3 x, radial;
            rimCrossing(*r, fresh.pose, x, radial);
            const double rho = glm::length(radial);
            const Vec3 v = s_.law_.velocity(fresh.phase, x);
            const Vec3& axis = fresh.pose.axis;
            gu = rho - r->radius + aim;
            slope = glm::dot(radial, line_.dir * (glm::dot(axis, v) / glm::dot(axis, line_.dir)) - v) / rho;
            close = std::abs(gu) <= kCornerGap - aim;
            return ++poses < kCornerSteps && std::isfinite(gu) && !close;
        };
        newtonBracket(g, a.u, b.u, ga + aim, gb + aim, 0.0);
        fresh.range = s_.tool_.intersectPart(s_.parts_[p], LocalLine::make(fresh.pose, line_));
        if (fresh.range.isEmpty()) return false;
        found_.add(fresh.range, fresh.u, p);
        // Kept only where the steps reached the rim: a narrower node's own steps may do better.
        if (close) {
            rimPoses_.push_back(fresh);
            at = &rimPoses_.back();
        } else {
            at = &fresh;
        }
    }
    const double u = at->u;
    const TurnPhase& phase = at->phase;
    const ToolPose& ps = at->pose;
    const Interval range = at->range;
    // The end, and the rim's point nearest it: both faces' planes through that point hold
    // the part, and the end lies `gap` from it.
    const Vec3 y = line_.at(upper ? range.hi : range.lo);
    const Vec3 offAxis = y - ps.tip - glm::dot(y - ps.tip, ps.axis) * ps.axis;
    const double rho = glm::length(offAxis);
    if (!(rho > 0.0)) return false;
    const Vec3 radial = offAxis / rho, point = ps.tip + r->z * ps.axis + r->radius * radial;
    const double gap = glm::length(y - point), bend = bendAt(r->z, r->radius);
    const Vec3 velocity = s_.law_.velocity(phase, point);
    // How far the line's points that matter reach beyond the end: within the care and the
    // node's sweep.
    const Interval reach = swept.intersect(care_.within());
    const double yt = upper ? range.hi : range.lo;
    const double beyond = std::max(0.0, upper ? reach.hi - yt : yt - reach.lo);
    // The planes tried: each face's, and where the line crosses one face's plane inward and
    // the other's outward, the plane of the rim's normal cone that holds the line.
    Vec3 normals[3];
    int planes = 0;
    for (int f = 0; f < 2; ++f) normals[planes++] = r->across[f] * radial + r->along[f] * ps.axis;
    const double d0 = glm::dot(normals[0], line_.dir), d1 = glm::dot(normals[1], line_.dir);
    if ((d0 > 0.0) != (d1 > 0.0)) normals[planes++] = glm::normalize(std::abs(d1) * normals[0] + std::abs(d0) * normals[1]);
    // Back over [a.u, u] (sign -1) and on over [u, b.u] (sign 1), each by one of the planes.
    for (const double sign : {-1.0, 1.0}) {
        const double w = sign < 0.0 ? u - a.u : b.u - u;
        bool bounded = false;
        for (int f = 0; f < planes && !bounded; ++f) {
            const Vec3& n = normals[f];
            const double out = upper ? glm::dot(n, line_.dir) : -glm::dot(n, line_.dir);
            // The least of s (out - omega tau) over the points beyond, s in [0, beyond], at
            // tau = 0 and w: concave in tau, against a convex right side.
            const double turn = s_.axisTurn_ * w;
            const double least0 = out >= 0.0 ? 0.0 : beyond * out;
            const double leastW = out >= turn ? 0.0 : beyond * (out - turn);
            bounded = gap - s_.epsilon_ < least0 &&
                      sign * w * glm::dot(n, velocity) + w * w * bend + gap * (1.0 + turn) - s_.epsilon_ < leastW;
        }
        if (!bounded) return false;
    }
    end = upper ? range.hi : range.lo;
    return true;
}

// Whether, where the line's end on that side lies on the same disk or cylinder face at
// poses a and b, that face bounds the points beyond the farthest end of a, b and (where
// the end dips past theirs) a pose solved between them, over the whole node (note o); that
// pose goes into O.
bool TurningSweep::LinearSearch::faceDip(std::size_t p, int upper, Solved& a, Solved& b, double& end) {
    if (!std::isfinite(s_.axisJerk_) || a.range.isEmpty() || b.range.isEmpty()) return false;
    const Crossing& ca = crossing(a, p, upper);
    const Crossing& cb = crossing(b, p, upper);
    if (ca.face != cb.face) return false;
    // The first and last faces up the meridian are the bottom and top disks (meridianFaces).
    const std::vector<MeridianFace>& faces = s_.faces_[p];
    const MeridianFace& face = faces[std::size_t(ca.face)];
    const bool disk = ca.face == 0 || ca.face == int(faces.size()) - 1;
    if (!disk && !(face.kind == MeridianFace::Kind::Cone && face.r0 == face.r1)) return false;
    const double w = b.u - a.u, turn = s_.axisTurn_, bend = s_.axisBend_, feed = s_.tipSpeed_;
    const double out = upper ? std::min(ca.across, cb.across) : -std::max(ca.across, cb.across);
    if (disk && !(out > 0.5 * turn * w)) return false;
    const double side = ca.face == 0 ? -1.0 : 1.0, radius = face.r0;
    const Vec3 beyond = upper ? line_.dir : -line_.dir;
    // F_z at a pose: a disk's H_z, or a cylinder's G_z; positive outside.
    const auto F = [&](const ToolPose& pose, const Vec3& z) {
        const Vec3 q = z - pose.tip;
        const double along = glm::dot(pose.axis, q);
        return disk ? side * (along - face.z0) : glm::dot(q, q) - along * along - radius * radius;
    };
    // How far below 0 F_z may fall at a point no deeper than epsilon.
    const double depth = disk ? s_.epsilon_ : s_.epsilon_ * (2.0 * radius - s_.epsilon_);
    const auto endOf = [&](const Interval& range) { return upper ? range.hi : range.lo; };
    const auto farther = [&](double s, double t) { return upper ? std::max(s, t) : std::min(s, t); };
    // Whether the points beyond line.at(t) lie outside every T(u) of the node but for
    // epsilon, by P through F_z at a, the pose `mid` at u and b, less the remainder;
    // `low` gets where P is least.
    const auto holds = [&](double t, double u, const ToolPose& mid, double& low) {
        const Vec3 z = line_.at(t);
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
        const double jerk = s_.axisJerk_ * reach + 3.0 * bend * feed;
        const double bound = disk ? jerk
                                  : 2.0 * reach * jerk + 6.0 * (turn * reach + feed) * (bend * reach + 2.0 * turn * feed);
        const ParabolaLow p2 = parabolaLow(a.u, F(a.pose, z), u, F(mid, z), b.u, F(b.pose, z));
        low = p2.u;
        return p2.value - bound * nodePolynomialMax(a.u, u, b.u) / 6.0 > -depth;
    };
    double t = farther(endOf(a.range), endOf(b.range)), deepest = 0.0;
    // The root's middle pose is kept (midPose_): most lines that reach here are the root's.
    const double um = 0.5 * (a.u + b.u);
    if (holds(t, um, um == s_.midPhase_.u ? s_.midPose_ : s_.law_.pose(um), deepest)) {
        end = t;
        return true;
    }
    if (!(deepest > a.u && deepest < b.u)) return false;
    const ToolPose pose = s_.law_.pose(deepest);
    const Interval range = s_.tool_.intersectPart(s_.parts_[p], LocalLine::make(pose, line_));
    if (range.isEmpty()) return false;
    found_.add(range, deepest, p);
    t = farther(t, endOf(range));
    double unused = 0.0;
    if (!holds(t, deepest, pose, unused)) return false;
    end = t;
    return true;
}

// Whether a node of width w that is not settled as a linear node has the line's points
// beyond its end poses' intervals (a, b) bounded by those poses' faces (note j), `swept`
// holding every point of the node deeper than epsilon; `aim` lets notes k and l solve
// poses to that end.
bool TurningSweep::LinearSearch::anchoredSettled(std::size_t p, double w, std::uint32_t a, std::uint32_t b, const Interval& swept,
                                             bool aim) {
    Solved* const ends[2] = {&solved_[a], &solved_[b]};
    const Interval hull = ends[0]->range.hull(ends[1]->range);
    if (hull.isEmpty()) return false;
    // The model moves on from pose a (sign 1) and back from pose b.
    const auto stretch = [&](int e, int upper, double cut) {
        return this->stretch(*ends[e], p, upper, cut, e == 0 ? 1.0 : -1.0);
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
            (corner(p, upper, *ends[0], *ends[1], swept, aimed) || graze(p, upper, *ends[0], *ends[1], aimed)))
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
    return held(cut) || bridge(p, cut, ends[0]->u, ends[1]->u);
}

bool TurningSweep::LinearSearch::bridge(std::size_t p, const Interval& cut, double ua, double ub) {
    for (int step = 0; step < kBridgeSteps; ++step) {
        const Interval gap = care_.firstGap(cut);
        if (gap.isEmpty()) return true;
        const turning::Piece* left = nullptr;
        const turning::Piece* right = nullptr;
        for (const turning::Piece& q : found_.pieces()) {
            if (q.range.hi == gap.lo) left = &q;
            if (q.range.lo == gap.hi) right = &q;
        }
        if (!left || !right || left->nodeHi != 0 || right->nodeLo != 0) return false;
        const double uL = left->uHi, uR = right->uLo;
        if (uL == uR || std::min(uL, uR) < ua || std::max(uL, uR) > ub) return false;
        // The poses' intervals taken as moving linearly from uL's, [left.lo, gap.lo], to uR's,
        // [gap.hi, right.hi]: the pose whose interval grown by epsilon still reaches the left
        // piece, or where one pose reaches both, the middle of those that do.
        const double lL = left->range.lo, hR = right->range.hi;
        const double reachesLeft = std::clamp((gap.lo + s_.epsilon_ - lL) / (gap.hi - lL), 0.0, 1.0);
        const double reachesRight = std::clamp((gap.hi - s_.epsilon_ - gap.lo) / (hR - gap.lo), 0.0, 1.0);
        const double s = reachesRight <= reachesLeft ? 0.5 * (reachesLeft + reachesRight) : reachesLeft;
        const double u = uL + s * (uR - uL);
        if (!(u != uL && u != uR)) return false;
        const ToolPose pose = s_.law_.pose(u);
        const LocalLine local = LocalLine::make(pose, line_);
        const Interval range = s_.tool_.intersectPart(s_.parts_[p], local);
        if (range.isEmpty()) return false;
        found_.add(range, u, p);
        const Interval within = intersectPieces(s_.grownEpsilon_[p], local).intersect(gap);
        if (!within.isEmpty()) found_.add(within, u, p);
    }
    return held(cut);
}

// A node's grown band swept along its move, along the line: empty where it misses the
// care. Four in ten of the nodes' sweeps miss the line (BM_TurningQuery, BM_TurningShortQuery),
// most of them beside the band or above or below it, which the narrowed bound tells for a
// fifth of the sweep's cost (the ball end's short rows 53 -> 37 ns a line).
Interval TurningSweep::LinearSearch::sweptWithin(const MoveSweep& sweep) const {
    return sweep.narrowBound(line_, care_.within()).isEmpty() ? Interval::empty() : sweep.intersect(line_);
}

// Linear nodes (notes h and i), band by band from the root down. The static poses of a band's
// part at both ends go into O where the root's sweep is not held without them (a line the grown
// band's sweep misses, or that a ball's capsules already hold, needs neither); the static pose
// at a node's middle is its whole part's too.
void TurningSweep::LinearSearch::run() {
    // Whether the end poses' faces left the part's root open (note n).
    bool rootOpen = false;
    for (std::size_t b = 0; b < s_.models_.size(); ++b) {
        const std::size_t p = s_.models_[b].part;
        if (b == 0 || s_.models_[b - 1].part != p) {
            // The part's root, taken whole, settles all its bands at once: by its end poses'
            // faces (note n) where no ball's capsules come first, else by its sweep. Where the
            // end poses' faces left it open, its sweep settled few lines (BM_TurningQuery: 2 to
            // 7 in a hundred, most of them beside it; BM_TurningShortQuery none), so the bands
            // come at once: the long rows 0.94-0.99, the short 0.97-0.99.
            bool settled = false;
            if (s_.parts_.size() == 1 && s_.balls_.empty()) {
                addEnds(p);
                settled = anchoredSettled(p, 1.0, 0, 1, Interval::all(), false);
                rootOpen = !settled;
            }
            if (!settled && !rootOpen && s_.wholeRoots_[p]) {
                const Interval swept = sweptWithin(s_.wholeRoots_[p]->sweep);
                if (!held(swept) && endsAdded_ != p) addEnds(p);
                settled = held(swept);
            }
            if (settled) {
                while (b + 1 < s_.models_.size() && s_.models_[b + 1].part == p) ++b;
                continue;
            }
        }
        // A band of a part cut into several is searched only where the care reaches its heights.
        if (!s_.wholeRoots_[p] || reaches(s_.models_[b])) searchBand(b, rootOpen);
    }
}

// Note p: the heights a point x of the care takes above the tip, h(x, u) = a(u).(x - p(u)).
// Its rate is h' = a'.(x - p) - a.p', with |a'| <= omega and g(u) = a(u).p'(u) changing at
// |g'| = |a'.p' + a.p''| <= omega |p'| + K = L (K bounding |p''|, MotionLaw's acceleration bound
// at the tip: 0 on a straight line), so |g(u)| <= min(|g(0)| + L u, |g(1)| + L (1 - u)) <=
// (|g(0)| + |g(1)| + L) / 2, and likewise |x - p(u)| <= (|x - p(0)| + |x - p(1)| + |p'|max) / 2.
// With D bounding |h'| so, h(x, u) >= max(h(x, 0) - D u, h(x, 1) - D (1 - u)) >= (h(x, 0) +
// h(x, 1) - D) / 2, and at most that sum plus D over 2; the mean of h at the end poses is linear
// along the line, and D convex (distances), so the care's ends bound both. A point deeper than
// epsilon inside T(u) is band b's to find only at band b's heights (note i), so a band whose
// heights the care never takes has nothing to find: its search is skipped, on a long cutter most
// of its bands (BM_TurningQuery's flat D10 x 50 in eight bands, a line crossing its tip).
bool TurningSweep::LinearSearch::reaches(const LinearPart& band) {
    if (!heights_) {
        const Interval& within = care_.within();
        heights_ = Interval::all();
        if (std::isfinite(within.lo) && std::isfinite(within.hi)) {
            const ToolPose& a = s_.startPose_;
            const ToolPose& b = s_.endPose_;
            const double g0 = std::abs(glm::dot(a.axis, s_.startTwist_.at(a.tip)));
            const double g1 = std::abs(glm::dot(b.axis, s_.endTwist_.at(b.tip)));
            const double rate = 0.5 * (g0 + g1 + s_.axisTurn_ * s_.tipSpeed_ + s_.pivotBend_);
            Interval mean;
            double spread = 0.0;
            for (const double t : {within.lo, within.hi}) {
                const Vec3 x = line_.at(t);
                const double h = 0.5 * (glm::dot(a.axis, x - a.tip) + glm::dot(b.axis, x - b.tip));
                mean = mean.hull(Interval{h, h});
                const double far = 0.5 * (glm::length(x - a.tip) + glm::length(x - b.tip) + s_.tipSpeed_);
                spread = std::max(spread, 0.5 * (rate + s_.axisTurn_ * far));
            }
            heights_ = Interval{mean.lo - spread, mean.hi + spread};
        }
    }
    return !heights_->intersect({band.lo, band.hi}).isEmpty();
}

void TurningSweep::LinearSearch::searchBand(std::size_t b, bool rootOpen) {
    const std::size_t p = s_.models_[b].part;
    const int leaf = s_.models_[b].leafLevel();
    if (solved_.size() > 2) solved_.resize(2);
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
        // Below the root, whose end poses are solved by now; above the leaves (note n).
        const bool withoutSweep = n.heap > 1 && heapLevel(n.heap) < leaf && s_.parts_.size() == 1 &&
                                  !solved_[n.a].range.isEmpty() && !solved_[n.b].range.isEmpty();
        if (n.heap > 1 && s_.parts_.size() == 1 &&
            anchoredSettled(p, heapWidth(n.heap), n.a, n.b, Interval::all(), withoutSweep))
            continue;
        // A part searched whole (one band) whose end poses' faces left its root open: the
        // root's grown sweep settles few of those lines (on BM_TurningShortQuery's flat end
        // at 0.2 degrees, one in eighteen, and its aimed test of notes k and l one in four),
        // so the root is split at once, its halves tried by note n before their sweeps.
        const bool splitRoot = n.heap == 1 && rootOpen && !s_.wholeRoots_[p] && leaf > 0;
        const LinearNode* node = nullptr;
        if (!splitRoot && !withoutSweep) {
            node = &s_.linearNode(b, n.heap, scratch);
            const Interval swept = sweptWithin(node->sweep);
            if (heapLevel(n.heap) == leaf) {  // closed: the band's own sweep along the node's move
                if (!swept.isEmpty()) found_.add(swept, node->middleU, node->middleU, b, n.heap);
                continue;
            }
            if (held(swept)) continue;  // settled: the grown band's sweep is held
            if (n.heap == 1 && endsAdded_ != p) {
                addEnds(p);
                if (held(swept)) continue;
            }
            if (s_.parts_.size() == 1 && anchoredSettled(p, node->width, n.a, n.b, swept, true)) continue;
        }
        const double middleU = node ? node->middleU : splitRoot ? s_.midPhase_.u : 0.5 * (solved_[n.a].u + solved_[n.b].u);
        const TurnPhase middlePhase = node ? node->phase : splitRoot ? s_.midPhase_ : s_.law_.phase(middleU);
        const ToolPose middlePose = node ? node->middle : splitRoot ? s_.midPose_ : s_.law_.pose(middlePhase);
        const Interval middle = s_.tool_.intersectPart(s_.parts_[p], LocalLine::make(middlePose, line_));
        if (!middle.isEmpty()) found_.add(middle, middleU, p);
        const std::uint32_t m = std::uint32_t(solved_.size());
        solved_.push_back({middleU, middlePose, middle, {}, middlePhase});
        stack[top++] = {2 * n.heap + 1, m, n.b};
        stack[top++] = {2 * n.heap, n.a, m};
    }
}

std::vector<TurningSweep::LinearSearch::Solved>& TurningSweep::LinearSearch::threadSolved() {
    static thread_local std::vector<Solved> solved;
    return solved;
}

}  // namespace dexelmill
