/// @file kinematics.h
/// @brief Machine kinematics: a machine's rotary axes and what their angles do to the tool's pose
/// in the part frame. The program readers call it; the sweep sees only the motion law it gives
/// (rotary_motion.h).
///
/// Frames. The machine frame is where X, Y and Z move the tool; at every rotary angle zero the part
/// frame coincides with it. A table axis turns what it carries (the part) by its angle, right-handed
/// about its direction, around the line through its pivot (machine frame, all angles zero). A head
/// axis turns the tool the same way, around a line through its pivot given relative to the tool
/// tip at all angles zero. The tool extends from its tip along +z of the machine frame while the
/// head axes are at zero.
///
/// Two modes, as LinuxCNC's switchable kinematics (M428 / M429) and Fanuc's G43.4 / G49:
///  - tool centre point control (TCP): X Y Z are the tip in the part frame; the tip runs straight
///    there and the angles run linearly, so only the axis follows the kinematics;
///  - identity: X Y Z and the angles are the machine's joints, all linear in time; the tip's path
///    in the part frame is the joint path carried by the tables' turns, a curve.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/machine/rotary_motion.h"

namespace dexelmill {

/// @brief The farthest (mm, per coordinate) a machine description may put a pivot: as far as a
/// program's positions may reach (kMaxCoordinateMm), where rounding still keeps what the axis
/// turns (a pivot at 1e300 mm would round every position it turns to itself).
constexpr double kMaxPivotMm = 1e9;

/// @brief One rotary axis of a machine.
struct RotaryAxisSpec {
    char letter = 'A';              ///< 'A', 'B' or 'C'
    bool onTable = true;            ///< true: turns the part; false: turns the tool (a head)
    Vec3 direction{1.0, 0.0, 0.0};  ///< unit
    Vec3 pivot{0.0};                ///< a point of its line (see the file comment for its frame)
};

/// @brief Rotary angles in degrees, by letter A, B, C (an axis a machine lacks stays 0).
struct RotaryAngles {
    double deg[3] = {0.0, 0.0, 0.0};
    double operator[](char letter) const { return deg[letter - 'A']; }
    double& operator[](char letter) { return deg[letter - 'A']; }
    bool operator==(const RotaryAngles& o) const {
        return deg[0] == o.deg[0] && deg[1] == o.deg[1] && deg[2] == o.deg[2];
    }
    bool operator!=(const RotaryAngles& o) const { return !(*this == o); }
};

/// @brief A machine: its rotary axes in chain order (the tables from the machine's base out to the
/// part, then the heads from the base out to the tool).
struct Machine {
    std::string name;
    std::vector<RotaryAxisSpec> axes;
    /// Whether programs start with tool centre point control on (LinuxCNC's sim configs start in
    /// identity kinematics, so the built-ins do not).
    bool tcpAtStart = false;

    /// @brief Whether the machine has a rotary axis with this letter.
    bool has(char letter) const;
    /// @brief The tool axis in the part frame at these angles (unit).
    Vec3 toolAxis(const RotaryAngles& angles) const;
    /// @brief Identity kinematics: the part-frame tip for machine joints `joints` at `angles`.
    Vec3 partFromJoints(const Vec3& joints, const RotaryAngles& angles) const;
    /// @brief The inverse: the joints that put the tip at part-frame `tip` at `angles`.
    Vec3 jointsFromPart(const Vec3& tip, const RotaryAngles& angles) const;
    /// @brief The motion law of a move from angles `from` to `to`: with TCP the tip runs straight
    /// in the part frame; in identity mode it is carried, from joints `jointsFrom` to `jointsTo`.
    RotaryMotion motion(const RotaryAngles& from, const RotaryAngles& to, bool tcp, const Vec3& jointsFrom,
                        const Vec3& jointsTo) const;
    /// @brief Whether no head axis turns between `from` and `to`.
    bool headsStill(const RotaryAngles& from, const RotaryAngles& to) const;
};

/// @brief The built-in machines, by name:
///  - `xyzac-trt`: LinuxCNC's sim config of that name (A tilting table about x, pivot y 20, z 10
///    from C's; C rotary table about z at the origin);
///  - `xyzbc-trt`: LinuxCNC's (B tilting table about y, pivot x -20, z -15 from C's; C about z);
///  - `xyza`: a 4-axis rotary table A about the x axis through the origin.
std::vector<std::string> builtinMachineNames();

/// @brief A built-in machine by name, or a machine described in a JSON file:
/// `{"name": ..., "tcp_at_start": false, "axes": [{"letter": "A", "on": "table" | "head",
///   "direction": [x, y, z], "pivot": [x, y, z]}, ...]}` (mm; axes in chain order).
/// The file is read by `read` where one is given (a job's FileSource, path/toolpath.h: none where
/// it has no such file), else from disk.
/// @throw Error naming the file (and the JSON error's place) or listing the built-ins.
Machine loadMachine(const std::string& nameOrFile,
                    const std::function<std::optional<std::string>(const std::string&)>& read = {});

/// @brief Parses a machine description (the JSON of loadMachine) from text.
/// @throw ParseError with the file's name and the place of the fault.
Machine parseMachine(const std::string& text, const std::string& fileName);

}  // namespace dexelmill
