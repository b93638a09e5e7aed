#include "dexelmill/path/motion.h"

#include <algorithm>
#include <cmath>

#include "dexelmill/geometry/rotation.h"
#include "dexelmill/path/toolpath.h"

namespace dexelmill {

MotionLaw::MotionLaw(const Move& move) : start_(move.start), feed_(move.feed()), toolAxis_(move.axis) {
    if (move.rotary) {
        const RotaryMotion& r = *move.rotary;
        turns_ = r.turns;
        toolAxis_ = r.toolAxis;
        carried_ = r.tipCarried;
        machineStart_ = r.machineStart;
        machineFeed_ = r.machineEnd - r.machineStart;
        heads_ = r.headTurns;
        return;
    }
    if (!move.startAxis) return;
    // The great circle from a0 to a1 is the turn about k = a0 x a1 / |a0 x a1| by their angle.
    const Vec3 a0 = *move.startAxis;
    const Vec3 k = glm::cross(a0, move.axis);
    const double s = glm::length(k);
    toolAxis_ = a0;
    if (s == 0.0) return;  // parallel (opposite axes are refused by the sweep)
    RotaryTurn turn;
    turn.direction = k / s;
    turn.pivot = move.start;
    turn.to = std::atan2(s, glm::dot(a0, move.axis));
    turns_.push_back(turn);
}

Vec3 MotionLaw::rotate(std::size_t i, double u, const Vec3& v) const {
    const RotaryTurn& t = turns_[i];
    return rotateAbout(v, t.direction, t.from + u * (t.to - t.from));
}

Vec3 MotionLaw::rotateHead(std::size_t j, double u, const Vec3& v) const {
    const RotaryTurn& h = heads_[j];
    return rotateAbout(v, h.direction, h.from + u * (h.to - h.from));
}

Vec3 MotionLaw::headPoint(double u, Vec3 v) const {
    for (std::size_t j = heads_.size(); j-- > 0;) v = heads_[j].pivot + rotateHead(j, u, v - heads_[j].pivot);
    return v;
}

// rho_j bounds |z_j - c_j| (the chain of turnBound); |H v| = |z_0| <= rho_0 + |c_0|.
double MotionLaw::headBounds(double reach, double& turn) const {
    if (heads_.empty()) return reach;
    double rho = reach + glm::length(heads_.back().pivot);
    for (std::size_t j = heads_.size(); j-- > 0;) {
        if (j + 1 < heads_.size()) rho += glm::length(heads_[j + 1].pivot - heads_[j].pivot);
        turn += std::abs(heads_[j].to - heads_[j].from) * rho;
    }
    return rho + glm::length(heads_.front().pivot);
}

ToolPose MotionLaw::pose(double u) const {
    ToolPose p;
    Vec3 axis = toolAxis_;
    for (std::size_t j = heads_.size(); j-- > 0;) axis = rotateHead(j, u, axis);
    for (std::size_t i = turns_.size(); i-- > 0;) axis = rotate(i, u, axis);
    p.axis = glm::normalize(axis);
    if (!carried_) {
        p.tip = start_ + u * feed_;
        return p;
    }
    Vec3 x = machineStart_ + u * machineFeed_;
    if (!heads_.empty()) x += headPoint(u, Vec3(0.0));
    for (std::size_t i = turns_.size(); i-- > 0;) x = turns_[i].pivot + rotate(i, u, x - turns_[i].pivot);
    p.tip = x;
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
Vec3 MotionLaw::velocity(double u, const Vec3& point) const {
    Vec3 v(0.0);
    if (!carried_) {
        const Vec3 tip = start_ + u * feed_;
        for (std::size_t i = 0; i < turns_.size(); ++i) {
            Vec3 w = turns_[i].direction * (turns_[i].to - turns_[i].from);
            for (std::size_t j = i; j-- > 0;) w = rotate(j, u, w);
            v += glm::cross(w, point - tip);
        }
        return feed_ + v;
    }
    Vec3 y = point;
    for (std::size_t i = 0; i < turns_.size(); ++i) {
        const RotaryTurn& t = turns_[i];
        Vec3 term = (t.to - t.from) * glm::cross(t.direction, y - t.pivot);
        for (std::size_t j = i; j-- > 0;) term = rotate(j, u, term);
        v += term;
        // y_{i+1} = c_i + R_i^T (y_i - c_i): the rotation by minus the angle.
        y = t.pivot + rotateAbout(y - t.pivot, t.direction, -(t.from + u * (t.to - t.from)));
    }
    Vec3 drift = machineFeed_;
    Vec3 z = y - (machineStart_ + u * machineFeed_);
    for (std::size_t j = 0; j < heads_.size(); ++j) {
        const RotaryTurn& h = heads_[j];
        Vec3 term = (h.to - h.from) * glm::cross(h.direction, z - h.pivot);
        for (std::size_t k = j; k-- > 0;) term = rotateHead(k, u, term);
        drift += term;
        // z_{j+1} = c_j + R_j^T (z_j - c_j): the rotation by minus the angle.
        z = h.pivot + rotateAbout(z - h.pivot, h.direction, -(h.from + u * (h.to - h.from)));
    }
    for (std::size_t j = turns_.size(); j-- > 0;) drift = rotate(j, u, drift);
    return v + drift;
}

// Carried: |y_i - c_i| = |y_{i+1} - c_i| <= |y_{i+1} - c_{i+1}| + |c_{i+1} - c_i| (T_{i+1} keeps
// distances to c_{i+1}), and the innermost y_n = x + H v lies within headBounds' reach of the
// machine-frame point x, whose distance to c_{n-1} is convex along its segment, so largest at an
// end. The heads' the same: |z_j - c_j| <= |z_{j+1} - c_{j+1}| + |c_{j+1} - c_j|, and the
// innermost z_m = v has |v - c_{m-1}| <= reach + |c_{m-1}|.
double MotionLaw::speedBound(double reach) const {
    return glm::length(carried_ ? machineFeed_ : feed_) + turnBound(reach);
}

double MotionLaw::turnBound(double reach) const {
    double v = 0.0;
    if (!carried_) {
        for (const RotaryTurn& t : turns_) v += std::abs(t.to - t.from) * reach;
        return v;
    }
    const double headReach = headBounds(reach, v);
    if (turns_.empty()) return v;
    const Vec3& last = turns_.back().pivot;
    double rho = std::max(glm::length(machineStart_ - last), glm::length(machineStart_ + machineFeed_ - last)) +
                 headReach;
    for (std::size_t i = turns_.size(); i-- > 0;) {
        if (i + 1 < turns_.size()) rho += glm::length(turns_[i + 1].pivot - turns_[i].pivot);
        v += std::abs(turns_[i].to - turns_[i].from) * rho;
    }
    return v;
}

}  // namespace dexelmill
