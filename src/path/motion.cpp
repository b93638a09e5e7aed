#include "dexelmill/path/motion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "dexelmill/error.h"
#include "dexelmill/geometry/rotation.h"
#include "dexelmill/geometry/tolerance.h"
#include "dexelmill/path/toolpath.h"

namespace dexelmill {

namespace {

/// Poses axisTurnBound samples per radian of the rates' sum, and at most: its bound exceeds the
/// largest turning rate by at most rates max(rates, 1) / 64, 1.6 % of the rates' sum up to a
/// radian. A real program's move turns its axes by a hundredth of a radian or so: one sample,
/// where 32 took 30,000 instructions a sweep, 4 % of the impeller's cut at 0.5 mm.
constexpr int kAxisTurnSamples = 32;

/// The first `count` turns of a chain at a phase, applied to a vector: R_0 ... R_{count-1} v, the
/// chain's first turn's cosine and sine at index `first` of the phase's.
Vec3 turnVector(const std::vector<RotaryTurn>& chain, const TurnPhase& phase, std::size_t first, std::size_t count,
                Vec3 v) {
    for (std::size_t i = count; i-- > 0;) v = rotateAbout(v, chain[i].direction, phase.c[first + i], phase.s[first + i]);
    return v;
}

/// The cosine and sine of angle(t) for each turn t, the heads' first: a TurnPhase's or TurnStep's.
template <class Angle>
void turnTrig(const std::vector<RotaryTurn>& heads, const std::vector<RotaryTurn>& turns, Angle&& angle,
              std::array<double, kMaxTurns>& c, std::array<double, kMaxTurns>& s) {
    std::size_t i = 0;
    for (const std::vector<RotaryTurn>* chain : {&heads, &turns})
        for (const RotaryTurn& t : *chain) {
            const double a = angle(t);
            c[i] = std::cos(a);
            s[i++] = std::sin(a);
        }
}

/// Adds to `sum` a chain's part of a point's velocity (see velocity), the point given as y_0 in
/// the frame the chain's first turn acts in; leaves y at y_n, in the frame inside its last turn.
void addChainVelocity(const std::vector<RotaryTurn>& chain, const TurnPhase& phase, std::size_t first, Vec3& y,
                      Vec3& sum) {
    for (std::size_t i = 0; i < chain.size(); ++i) {
        const RotaryTurn& t = chain[i];
        sum += turnVector(chain, phase, first, i, (t.to - t.from) * glm::cross(t.direction, y - t.pivot));
        // y_{i+1} = c_i + R_i^T (y_i - c_i): the rotation by minus the angle.
        y = t.pivot + rotateAbout(y - t.pivot, t.direction, phase.c[first + i], -phase.s[first + i]);
    }
}

/// Given rho, a bound on |y_n - c_{n-1}| inside a chain's last turn, adds sum_i |to_i - from_i|
/// rho_i to `turn` (rho_i bounding |y_i - c_i|, see turnBound) and returns rho_0.
double chainBound(const std::vector<RotaryTurn>& chain, double rho, double& turn) {
    for (std::size_t i = chain.size(); i-- > 0;) {
        if (i + 1 < chain.size()) rho += glm::length(chain[i + 1].pivot - chain[i].pivot);
        turn += std::abs(chain[i].to - chain[i].from) * rho;
    }
    return rho;
}

}  // namespace

MotionLaw::MotionLaw(const Move& move) : start_(move.start), feed_(move.feed()), toolAxis_(move.axis) {
    if (move.rotary) {
        const RotaryMotion& r = *move.rotary;
        turns_ = r.turns;
        toolAxis_ = r.toolAxis;
        carried_ = r.tipCarried;
        machineStart_ = r.machineStart;
        machineFeed_ = r.machineEnd - r.machineStart;
        heads_ = r.headTurns;
        if (turns_.size() + heads_.size() > kMaxTurns)
            throw Error("a move turns about " + std::to_string(turns_.size() + heads_.size()) + " axes; at most " +
                        std::to_string(kMaxTurns) + " (A, B and C) are supported");
        return;
    }
    if (!move.startAxis) return;
    // The great circle from a0 to a1 is the turn about k = a0 x a1 / |a0 x a1| by their angle.
    const Vec3 a0 = *move.startAxis;
    const Vec3 k = glm::cross(a0, move.axis);
    const double s = glm::length(k);
    toolAxis_ = a0;
    if (s <= tol::kParallel && glm::dot(a0, move.axis) < 0.0)
        throw Error("the axes are opposite: no one great circle joins them");
    if (s == 0.0) return;  // the same axis: no turn
    RotaryTurn turn;
    turn.direction = k / s;
    turn.pivot = move.start;
    turn.to = std::atan2(s, glm::dot(a0, move.axis));
    turns_.push_back(turn);
}

TurnPhase MotionLaw::phase(double u) const {
    TurnPhase p;
    p.u = u;
    turnTrig(heads_, turns_, [u](const RotaryTurn& t) { return t.from + u * (t.to - t.from); }, p.c, p.s);
    return p;
}

TurnStep MotionLaw::step(double du) const {
    TurnStep st;
    st.du = du;
    turnTrig(heads_, turns_, [du](const RotaryTurn& t) { return du * (t.to - t.from); }, st.c, st.s);
    return st;
}

TurnPhase MotionLaw::advance(const TurnPhase& phase, const TurnStep& step) const {
    TurnPhase p;
    p.u = phase.u + step.du;
    for (std::size_t i = 0; i < heads_.size() + turns_.size(); ++i) {
        p.c[i] = phase.c[i] * step.c[i] - phase.s[i] * step.s[i];
        p.s[i] = phase.s[i] * step.c[i] + phase.c[i] * step.s[i];
    }
    return p;
}

ToolPose MotionLaw::pose(const TurnPhase& phase) const {
    const std::size_t h = heads_.size();
    // R_0 ... R_{count-1} v for the chain whose first turn's phase is at index `first`.
    const auto turn = [&](const std::vector<RotaryTurn>& chain, std::size_t first, Vec3 v) {
        for (std::size_t i = chain.size(); i-- > 0;)
            v = rotateAbout(v, chain[i].direction, phase.c[first + i], phase.s[first + i]);
        return v;
    };
    // T_0 ... T_{n-1} x, each turn about its pivot.
    const auto turnPoint = [&](const std::vector<RotaryTurn>& chain, std::size_t first, Vec3 x) {
        for (std::size_t i = chain.size(); i-- > 0;)
            x = chain[i].pivot + rotateAbout(x - chain[i].pivot, chain[i].direction, phase.c[first + i], phase.s[first + i]);
        return x;
    };
    ToolPose p;
    p.axis = glm::normalize(turn(turns_, h, turn(heads_, 0, toolAxis_)));
    const double u = phase.u;
    if (!carried_) {
        p.tip = start_ + u * feed_;
        return p;
    }
    Vec3 x = machineStart_ + u * machineFeed_;
    if (!heads_.empty()) x += turnPoint(heads_, 0, Vec3(0.0));
    p.tip = turnPoint(turns_, h, x);
    return p;
}

// A tool point is y = G(u) (x(u) + H(u) v) (carried; x the machine-frame point, x' = m1 - m0) or
// y = p(u) + Q(u) v (on the line; v fixed). With y_0 = y and y_{i+1} = T_i^{-1} y_i, so that
// y_i = T_i y_{i+1}, the derivative of T_i in its angle at y_{i+1} is rate_i d_i x (y_i - c_i),
// carried to the part frame by R_0 ... R_{i-1}; the heads' the same on z_0 = H v = y_n - x,
// z_{j+1} = T_hj^{-1} z_j, carried by the heads before j and then by Q:
//   y' = sum_i Q_{<i} (rate_i d_i x (y_i - c_i)) + Q (x' + sum_j Q_h<j (rate_j d_j x (z_j - c_j)))
//                                                                       (carried)
//   y' = f + w x (y - p),  w = sum_i rate_i Q_{<i} d_i                  (on the line)
Vec3 MotionLaw::velocity(double u, const Vec3& point) const { return velocity(phase(u), point); }

Vec3 MotionLaw::velocity(const TurnPhase& phase, const Vec3& point) const {
    const std::size_t h = heads_.size();
    const double u = phase.u;
    Vec3 v(0.0);
    if (!carried_) {
        const Vec3 tip = start_ + u * feed_;
        for (std::size_t i = 0; i < turns_.size(); ++i) {
            const Vec3 w = turnVector(turns_, phase, h, i, turns_[i].direction * (turns_[i].to - turns_[i].from));
            v += glm::cross(w, point - tip);
        }
        return feed_ + v;
    }
    Vec3 y = point;
    addChainVelocity(turns_, phase, h, y, v);
    Vec3 drift = machineFeed_;
    Vec3 z = y - (machineStart_ + u * machineFeed_);
    addChainVelocity(heads_, phase, 0, z, drift);
    drift = turnVector(turns_, phase, h, turns_.size(), drift);
    return v + drift;
}

// A rigid motion's velocity field is v(y) = v(o) + W x (y - o), W its angular velocity. With the
// tip on the line, v(y) = f + sum_i w_i x (y - p): o = p, W = sum_i w_i. A carried tip's chains
// give W by differences: v(o + e_x) - v(o) = W x e_x = (0, W_z, -W_y) and v(o + e_y) - v(o) =
// (-W_z, 0, W_x).
Twist MotionLaw::twist(const TurnPhase& phase) const {
    Twist t;
    if (!carried_) {
        const std::size_t h = heads_.size();
        t.origin = start_ + phase.u * feed_;
        t.linear = feed_;
        for (std::size_t i = 0; i < turns_.size(); ++i)
            t.angular += turnVector(turns_, phase, h, i, turns_[i].direction * (turns_[i].to - turns_[i].from));
        return t;
    }
    t.origin = pose(phase).tip;
    t.linear = velocity(phase, t.origin);
    const Vec3 dx = velocity(phase, t.origin + Vec3(1.0, 0.0, 0.0)) - t.linear;
    const Vec3 dy = velocity(phase, t.origin + Vec3(0.0, 1.0, 0.0)) - t.linear;
    t.angular = Vec3(dy.z, -dx.z, dx.y);
    return t;
}

// Carried: |y_i - c_i| = |y_{i+1} - c_i| <= |y_{i+1} - c_{i+1}| + |c_{i+1} - c_i| (T_{i+1} keeps
// distances to c_{i+1}), and the innermost y_n = x + H v lies within headBounds' reach of the
// machine-frame point x, whose distance to c_{n-1} is convex along its segment, so largest at an
// end. The heads' the same: |z_j - c_j| <= |z_{j+1} - c_{j+1}| + |c_{j+1} - c_j|, and the
// innermost z_m = v has |v - c_{m-1}| <= reach + |c_{m-1}|.
double MotionLaw::speedBound(double reach) const {
    return glm::length(carried_ ? machineFeed_ : feed_) + turnBound(reach);
}

// The axis is a(u) = Q(u) q with q fixed (Q including the heads' turns, innermost), so
// a' = w x a, w the angular velocity of the rigid motion: the difference of the velocities of the
// tip and the point one unit up the axis. |a''| <= |Q''| <= (sum_i |rate_i|)^2 by the product rule
// (each turn at a constant rate), so between samples u_k = (k + 1/2) / N, every u being within
// 1 / (2N) of one, |a'(u)| <= max_k |a'(u_k)| + (sum_i |rate_i|)^2 / (2N); N = min(32, ceil(32
// rates)) makes that at most rates max(rates, 1) / 64. And |a'| <= |w| <= sum_i |rate_i|.
double MotionLaw::rateSum() const {
    double rates = 0.0;
    for (const std::vector<RotaryTurn>* chain : {&turns_, &heads_})
        for (const RotaryTurn& t : *chain) rates += std::abs(t.to - t.from);
    return rates;
}

double MotionLaw::axisTurnBound() const {
    const double rates = rateSum();
    if (rates == 0.0) return 0.0;
    const int samples = int(std::min(double(kAxisTurnSamples), std::ceil(kAxisTurnSamples * rates)));
    double largest = 0.0;
    for (int k = 0; k < samples; ++k) {
        const TurnPhase at = phase((k + 0.5) / samples);
        const ToolPose p = pose(at);
        largest = std::max(largest, glm::length(velocity(at, p.tip + p.axis) - velocity(at, p.tip)));
    }
    return std::min(rates, largest + rates * rates / (2.0 * samples));
}

// Identity kinematics: the tool point v (relative to the tip at every angle zero, |v| <= reach)
// sits at y = z_0, z_i = c_i + R_i(u) (z_{i+1} - c_i) down the tables' chain, z_n = x(u) + h(u)
// with x the joints' point, linear (x' = F, x'' = 0), and h = e_0 the heads' chain's image of v:
// e_j = p_j + S_j(u) (e_{j+1} - p_j), e_m = v, still (e_m' = e_m'' = 0). Down either chain
//   z_i' = R_i' (z_{i+1} - c_i) + R_i z_{i+1}',
//   z_i'' = R_i'' (z_{i+1} - c_i) + 2 R_i' z_{i+1}' + R_i z_{i+1}'',
// and with |R_i' q| <= w_i |q|, |R_i'' q| <= w_i^2 |q| and rho_i >= |z_{i+1} - c_i| as in
// chainBound: |z_i'| <= w_i rho_i + |z_{i+1}'|, |z_i''| <= w_i^2 rho_i + 2 w_i |z_{i+1}'| + |z_{i+1}''|.
// The heads' chain starts from 0 and 0 with sigma_{m-1} = reach + |p_{m-1}| >= |v - p_{m-1}|; the
// tables' from |z_n'| <= |F| + |h'| and |z_n''| <= |h''|, with |z_n - c_{n-1}| at most the joints'
// point's distance (largest at an end of its segment) plus |h| <= sigma_0 + |p_0| (turnBound's
// headReach). Every rho_i and sigma_j is a constant plus reach, so by induction the bound is a
// constant plus (sum of every turn's rate)^2 reach: axisBendBound's rate, as the header says.
double MotionLaw::axisPointAccelerationBound(double reach) const {
    const double rate = rateSum();
    if (!carried_) return rate * rate * reach;
    // Down a chain from its innermost point, rho bounding that point's distance from the
    // chain's last pivot: speed and accel, the bounds on |z'| and |z''|, grow turn by turn.
    double speed = 0.0, accel = 0.0;
    const auto down = [&](const std::vector<RotaryTurn>& chain, double rho) {
        for (std::size_t i = chain.size(); i-- > 0;) {
            if (i + 1 < chain.size()) rho += glm::length(chain[i + 1].pivot - chain[i].pivot);
            const double w = std::abs(chain[i].to - chain[i].from);
            accel += w * w * rho + 2.0 * w * speed;
            speed += w * rho;
        }
        return rho;
    };
    const double headReach =
        heads_.empty() ? reach : down(heads_, reach + glm::length(heads_.back().pivot)) + glm::length(heads_.front().pivot);
    if (turns_.empty()) return accel;
    speed += glm::length(machineFeed_);
    const Vec3& last = turns_.back().pivot;
    down(turns_,
         std::max(glm::length(machineStart_ - last), glm::length(machineStart_ + machineFeed_ - last)) + headReach);
    return accel;
}

double MotionLaw::axisBendBound() const {
    const double rate = rateSum();
    return rate * rate;
}

double MotionLaw::axisJerkBound() const {
    if (carried_) return std::numeric_limits<double>::infinity();
    const double rate = rateSum();
    return rate * rate * rate;
}

double MotionLaw::turnBound(double reach) const {
    double v = 0.0;
    if (!carried_) {
        for (const RotaryTurn& t : turns_) v += std::abs(t.to - t.from) * reach;
        return v;
    }
    // |H v| = |z_0| <= rho_0 + |c_0| for the heads' chain, whose innermost z_m = v lies within
    // reach + |c_{m-1}| of its last pivot.
    const double headReach = heads_.empty() ? reach
                                            : chainBound(heads_, reach + glm::length(heads_.back().pivot), v) +
                                                  glm::length(heads_.front().pivot);
    if (turns_.empty()) return v;
    const Vec3& last = turns_.back().pivot;
    chainBound(turns_,
               std::max(glm::length(machineStart_ - last), glm::length(machineStart_ + machineFeed_ - last)) + headReach,
               v);
    return v;
}

Move subMove(const Move& move, double u0, double u1) {
    const MotionLaw law(move);
    Move piece = move;
    const ToolPose first = law.pose(u0), last = law.pose(u1);
    // A straight tip's segment cut by its own formula (the law's pose is that, for a machine's
    // move under TCP too); a carried tip's ends are the law's poses.
    const bool carried = move.rotary && move.rotary->tipCarried;
    piece.start = carried ? first.tip : move.start + u0 * move.feed();
    piece.end = carried ? last.tip : move.start + u1 * move.feed();
    if (!move.turns()) return piece;
    piece.startAxis = first.axis;
    piece.axis = last.axis;
    if (move.rotary) {
        RotaryMotion r = *move.rotary;
        const auto cut = [u0, u1](RotaryTurn& t) {
            const double from = t.from, span = t.to - t.from;
            t.from = from + u0 * span;
            t.to = from + u1 * span;
        };
        for (RotaryTurn& t : r.turns) cut(t);
        for (RotaryTurn& t : r.headTurns) cut(t);
        const Vec3 joints = r.machineEnd - r.machineStart;
        r.machineStart = move.rotary->machineStart + u0 * joints;
        r.machineEnd = move.rotary->machineStart + u1 * joints;
        piece.rotary = std::make_shared<const RotaryMotion>(std::move(r));
    }
    return piece;
}

// The tip y(u) has |y''| <= K = axisPointAccelerationBound(0) over the move, so with n pieces of
// h = 1/n:
//  - sag: on a piece, y less its chord vanishes at both ends, and linear interpolation's remainder
//    bounds it by K h^2 / 8; n is the least that brings this within kTipPathSag (K = 0 where the
//    tip runs straight: one piece, exact);
//  - axis: every u lies within h / 2 of a pose, and the axis turns at most axisTurnBound() per unit
//    u, so it stays within that times h / 2 of the pose's;
//  - length: on a piece with chord c, d = c / h and e(t) = y'(t) - d, |e(t)| <= (1/h) int |y'(t) -
//    y'(s)| ds <= K h / 2, and int |e| <= K h^2 / 3. Since |d + e| <= |d| + (2 d.e + |e|^2) / (2|d|)
//    and int e = 0, the piece's length int |d + e| exceeds |c| by at most int |e|^2 / (2|d|) <=
//    K^2 h^4 / (8 |c|), and never by more than int |e| either: the smaller of the two, summed.
TipPath tipPath(const Move& move) {
    TipPath path;
    const Vec3 startAxis = move.startAxis ? *move.startAxis : move.axis;
    if (!(move.rotary && move.rotary->tipCarried)) {
        path.poses = {ToolPose{move.start, startAxis}, ToolPose{move.end, move.axis}};
        path.length = glm::length(move.feed());
        if (move.turns()) path.axisStep = MotionLaw(move).axisTurnBound() / 2.0;
        return path;
    }
    const MotionLaw law(move);
    const double accel = law.axisPointAccelerationBound(0.0);
    const int n = int(std::clamp(std::ceil(std::sqrt(accel / (8.0 * kTipPathSag))), 1.0, double(kMaxTipPathPieces)));
    const double h = 1.0 / n;
    path.sag = accel * h * h / 8.0;
    path.axisStep = law.axisTurnBound() * h / 2.0;
    path.poses.reserve(std::size_t(n) + 1);
    for (int k = 0; k <= n; ++k) path.poses.push_back(law.pose(double(k) * h));
    path.poses.front() = ToolPose{move.start, startAxis};
    path.poses.back() = ToolPose{move.end, move.axis};
    for (int k = 0; k < n; ++k) {
        const double chord = glm::length(path.poses[std::size_t(k) + 1].tip - path.poses[std::size_t(k)].tip);
        path.length += chord;
        const double coarse = accel * h * h / 3.0;
        path.lengthError += chord > 0.0 ? std::min(coarse, accel * accel * h * h * h * h / (8.0 * chord)) : coarse;
    }
    return path;
}

}  // namespace dexelmill
