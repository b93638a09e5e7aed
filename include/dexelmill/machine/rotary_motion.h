/// @file rotary_motion.h
/// @brief The law of a move that a machine's rotary axes make, as the machine's kinematics give it
/// (kinematics.h) and a Move carries it (path/toolpath.h, path/motion.h).
#pragma once

#include <vector>

#include "dexelmill/geometry/types.h"

namespace dexelmill {

/// @brief A rotation of the part frame about a fixed line (unit `direction` through `pivot`) by an
/// angle (radians) that runs linearly in u from `from` to `to`.
struct RotaryTurn {
    Vec3 direction{0.0, 0.0, 1.0};
    Vec3 pivot{0.0};
    double from = 0.0, to = 0.0;
};

/// @brief The motion law of a move that a machine's rotary axes make.
///
/// Write T_i(u) x = c_i + R_i(u) (x - c_i) for turn i (R_i the rotation about direction_i by its
/// angle at u) and G(u) = T_0 T_1 ... T_{n-1} (turn 0 outermost). The tool axis in the part frame
/// is Q(u) toolAxis, Q = R_0 R_1 ... R_{n-1}. The tip in the part frame:
///  - tool centre point control (tipCarried false): the straight line from the move's start to its
///    end, as for any move;
///  - identity kinematics (tipCarried true): G(u) applied to the machine-frame point
///    x(u) + H(u) 0, where x(u) runs linearly from machineStart to machineEnd and H(u) is the head
///    turns' map, the same composition of `headTurns` about pivots relative to x(u): a curve in
///    the part frame. A tool point v (relative to the tip at zero head angles) sits at
///    G(u) (x(u) + H(u) v), and the axis is Q(u) Q_H(u) toolAxis.
struct RotaryMotion {
    std::vector<RotaryTurn> turns;
    Vec3 toolAxis{0.0, 0.0, 1.0};  ///< unit, in the frame the turns act on
    bool tipCarried = false;
    Vec3 machineStart{0.0}, machineEnd{0.0};
    /// Identity kinematics only: the heads' turns, from the base out to the tool (pivots relative
    /// to the machine-frame point), when a head turns during the move; empty otherwise (then the
    /// heads' fixed offset and axis are in machineStart, machineEnd and toolAxis).
    std::vector<RotaryTurn> headTurns;
};

}  // namespace dexelmill
