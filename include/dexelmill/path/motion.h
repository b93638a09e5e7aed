/// @file motion.h
/// @brief How the tool moves during one move: the tool pose in the part frame as a function of the
/// move parameter u in [0, 1], for fixed-axis moves, APT MULTAX moves whose axis turns on a great
/// circle, and moves of a machine's rotary axes (machine/kinematics.h).
#pragma once

#include <array>
#include <cstddef>
#include <limits>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/machine/rotary_motion.h"
#include "dexelmill/tool/line_query.h"

namespace dexelmill {

struct Move;

/// @brief The most turns a motion law has: a machine's rotary axes (tables and heads together)
/// are A, B and C at most, and an APT move turns about one axis.
constexpr std::size_t kMaxTurns = 3;

/// @brief Where a move's turns stand at one u: the cosine and sine of each turn's angle (the
/// heads' first, then the tables'), all that MotionLaw::pose needs beyond u. A search that bisects
/// [0, 1] steps from one phase to the next with products (MotionLaw::advance) instead of a sine and
/// a cosine per turn.
struct TurnPhase {
    double u = 0.0;
    std::array<double, kMaxTurns> c{}, s{};
};

/// @brief How much each turn's angle changes over a step of u, as its cosine and sine.
struct TurnStep {
    double du = 0.0;
    std::array<double, kMaxTurns> c{}, s{};
};

/// @brief The most a phase reached by advance differs from the exact one, per step and per turn,
/// as a distance on the unit circle (so also a change of angle, in radians): the step's cosine and
/// sine are within an ulp of the unit circle, and the angle sum's two products and sum round by
/// at most another three half-ulps; four units of DBL_EPSILON bound both. After m steps the pose
/// moves a point at distance d from a turn's pivot by at most m n d kPhaseStepError for n turns:
/// for a 60-level search, 3 turns and d = 1 m, 1.6e-10 mm.
constexpr double kPhaseStepError = 4.0 * std::numeric_limits<double>::epsilon();

/// @brief The velocity field of a rigid motion at one instant: the tool point at y moves at
/// linear + angular x (y - origin) (mm per unit u).
struct Twist {
    Vec3 origin{0.0}, linear{0.0}, angular{0.0};
    Vec3 at(const Vec3& y) const { return linear + glm::cross(angular, y - origin); }
};

/// @brief The pose of the tool over a move, and how fast its points move. Every move is a rigid
/// motion of the tool: a fixed-axis move translates it; an APT move whose axis turns rotates it
/// about the fixed axis a0 x a1 by the angle between its axes, uniformly in u (one RotaryTurn);
/// a machine move follows its RotaryMotion.
class MotionLaw {
  public:
    /// @throw Error if the move turns about more than kMaxTurns axes, or its axes are opposite
    /// (no one great circle joins them).
    explicit MotionLaw(const Move& move);

    ToolPose pose(double u) const { return pose(phase(u)); }
    /// @brief The pose at phase.u, from the phase's cosines and sines.
    ToolPose pose(const TurnPhase& phase) const;
    /// @brief The turns' phase at u.
    TurnPhase phase(double u) const;
    /// @brief The turns' change over a step of du.
    TurnStep step(double du) const;
    /// @brief The phase at phase.u + step.du, by the angle sum (error: kPhaseStepError per step).
    TurnPhase advance(const TurnPhase& phase, const TurnStep& step) const;
    /// @brief The velocity (mm per unit u) at u of the tool point that is at `point` then.
    Vec3 velocity(double u, const Vec3& point) const;
    /// @brief As velocity(u, point), at a phase's u with its cosines and sines.
    Vec3 velocity(const TurnPhase& phase, const Vec3& point) const;
    /// @brief The velocity field at a phase, for a caller that asks for many points' velocities
    /// at one phase: twist(phase).at(y) is velocity(phase, y) up to rounding (a rigid motion's
    /// velocities are affine in the point), for a few products instead of a walk of the turns.
    Twist twist(const TurnPhase& phase) const;
    /// @brief The sum of the turns' rates, sum_i |to_i - from_i| (heads' turns included): radians
    /// per unit u, and over the whole move the most any direction the motion carries turns through.
    double rateSum() const;
    /// @brief A bound on |velocity| over the move for every tool point within `reach` of the tip:
    ///  - tip on the line: |f| + sum_i |to_i - from_i| reach, since a tool point moves as
    ///    y' = f + w x (y - p) with |w| <= sum_i |angle rate_i|;
    ///  - tip carried: |m1 - m0| + sum_i |to_i - from_i| rho_i, with rho_i bounding a tool point's
    ///    distance to pivot i in the frame turn i acts on (motion.cpp).
    double speedBound(double reach) const;
    /// @brief The part of speedBound that the turns make: how far, at most, a tool point strays
    /// from where the move's translation alone would take it.
    double turnBound(double reach) const;
    /// @brief A bound on |a'(u)| over the move (rad per unit u), a(u) the unit tool axis: how fast
    /// the axis's direction turns. The tool is a solid of revolution, so only this turn moves it:
    /// a turn about the axis itself, such as a rotary table's under an upright tool, does not.
    /// Never more than the sum of the turns' rates, which turnBound takes (motion.cpp).
    double axisTurnBound() const;
    /// @brief A bound on |y''(u)| (mm per unit u squared) over the move for every tool point y
    /// within `reach` of the tip (a point up the axis among them), and at reach 1 a bound on
    /// |a''(u)|.
    /// When the tip runs on the straight line, y = p(u) + Q(u) v with p'' = 0 and
    /// Q = R_0 ... R_{n-1}, each R_i a turn about a fixed direction at the constant rate w_i, so
    /// |R_i'| = |w_i|, |R_i''| = w_i^2 and by the product rule |Q''| <= (sum_i |w_i|)^2. In
    /// identity kinematics, where the machine carries the tip on a curve, turn by turn down its
    /// chains: the heads' turns swinging the tool about their pivots, then the tables' carrying
    /// that to the part frame (motion.cpp).
    double axisPointAccelerationBound(double reach) const;
    /// @brief A bound on |a''(u)|, a(u) = Q(u) a_0 the unit tool axis (heads' turns included):
    /// (sum_i |w_i|)^2, as for axisPointAccelerationBound, which grows with reach at exactly this
    /// rate: axisPointAccelerationBound(r) = axisPointAccelerationBound(0) + axisBendBound() r.
    double axisBendBound() const;
    /// @brief A bound on |a'''(u)| over the move, a(u) = Q(u) a_0 the unit tool axis with Q as in
    /// axisPointAccelerationBound: each R_i has |R_i'''| = |w_i|^3, so by the product rule
    /// |Q'''| <= (sum_i |w_i|)^3, heads' turns included. Infinite unless the tip runs on a
    /// straight line: the tests that take it (turning_linear_search.cpp, note o) need that too.
    double axisJerkBound() const;

  private:
    Vec3 start_{0.0}, feed_{0.0};
    std::vector<RotaryTurn> turns_;
    Vec3 toolAxis_{0.0, 0.0, 1.0};
    bool carried_ = false;
    Vec3 machineStart_{0.0}, machineFeed_{0.0};
    std::vector<RotaryTurn> heads_;  ///< RotaryMotion::headTurns
};

/// @brief The stretch [u0, u1] of a move (0 <= u0 < u1 <= 1) as a move of its own, whose pose at
/// s in [0, 1] is the move's at u0 + (u1 - u0) s, to rounding: the tip's segment cut at u0 and u1;
/// for an APT move whose axis turns, the axes there, on the same great circle at the same uniform
/// rate; for a machine's move, each turn's angles, the joints' segment and the heads' turns taken
/// at u0 and u1, which run linearly in u as the whole move's do. The union of a move's stretches'
/// poses is the move's, so is their swept volume.
Move subMove(const Move& move, double u0, double u1);

/// @brief The most the polyline tipPath takes a move's tip path as may stray from it, where its
/// pieces suffice: a tenth of the arcs' default chord tolerance (1e-3 mm), so that extents and
/// lengths read from it are as good as an arc's chords give.
constexpr double kTipPathSag = 1e-4;
/// @brief The most pieces tipPath cuts one move into (a table's ten turns with the tip 10 mm off
/// its axis take 7,025); past it the sag it reports grows.
constexpr int kMaxTipPathPieces = 1 << 16;

/// @brief A move's tip path as the polyline through its poses at u = k / n, k = 0..n (the ends
/// exactly the move's), with proven bounds on how far the path strays from it (motion.cpp).
struct TipPath {
    std::vector<ToolPose> poses;
    double sag = 0.0;          ///< the tip's path lies within this of the polyline's chords (mm)
    double axisStep = 0.0;     ///< the axis at every u lies within this (rad) of a pose's axis
    double length = 0.0;       ///< the chords' total: the path's length, or short of it by
    double lengthError = 0.0;  ///< at most this (mm)
};

/// @brief The tip path of a move: its two ends where the tip runs straight (a fixed axis, an APT
/// turn, a machine's move under TCP), else as many pieces as keep the sag within kTipPathSag.
TipPath tipPath(const Move& move);

}  // namespace dexelmill
