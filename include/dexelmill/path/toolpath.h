/// @file toolpath.h
/// @brief Moves, tool changes and diagnostics: what the program readers produce and the cutting
/// loop consumes. Positions in mm in the part frame.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dexelmill/error.h"
#include "dexelmill/geometry/types.h"
#include "dexelmill/path/motion.h"
#include "dexelmill/tool/tool.h"

namespace dexelmill {

/// @brief The largest coordinate (mm) a program may reach; readers reject a position beyond it
/// with a located error. The cutting loop clips any move to the stock exactly; this bound keeps the
/// rounding of the move's coordinates (1e-7 mm at 1e9 mm) below the sweep's accuracy.
constexpr double kMaxCoordinateMm = 1e9;

/// @brief The largest rotary angle (degrees) a program may turn an axis to; readers reject one
/// beyond it with a located error. 2,777 turns either way: its rounding (1e-10 degrees) moves a
/// tool point 1 m from the axis by 2e-9 mm.
constexpr double kMaxRotaryDegrees = 1e6;

/// @brief The most (degrees) one move may turn a rotary axis; readers reject more with a located
/// error. A turning sweep's work grows with the path its tool points travel (under a flat D4 at
/// 0.5 mm, a table turning 1,080 degrees in one move takes 0.13 s; 360 degrees while a head
/// turns 5, searched by static poses, 3.2 s), so ten turns in one block is as far as a program
/// is served, and an absurd angle cannot run the job out of time and memory.
constexpr double kMaxMoveTurnDegrees = 3600.0;

/// @brief Whether every coordinate of p is finite and within kMaxCoordinateMm.
inline bool withinReach(const Vec3& p) {
    return std::abs(p.x) <= kMaxCoordinateMm && std::abs(p.y) <= kMaxCoordinateMm && std::abs(p.z) <= kMaxCoordinateMm;
}

/// @brief Where a move came from: an index into ToolPath::files and a 1-based line (0: none).
struct SourceRef {
    std::uint32_t file = 0;
    std::int32_t line = 0;
};

/// @brief A linear cutter-location move F(u) = start + (end - start) u, u in [0, 1] (Eq. 1),
/// with a fixed unit tool axis: the tool extends from the CL point (its tip) along +axis.
///
/// A move whose program turns the tool axis on the way (an APT GOTO with a new i,j,k) keeps the
/// axis it starts from in `startAxis`; the cutting loop sweeps it turning (sweep/turning.h).
/// A move of a machine's rotary axes also carries its law in `rotary` (path/motion.h): then
/// start, end, startAxis and axis are its poses at u = 0 and 1, and the law says what lies
/// between. Both are empty for every fixed-axis move.
struct Move {
    Vec3 start{0.0};
    Vec3 end{0.0};
    Vec3 axis{0.0, 0.0, 1.0};  ///< the unit axis at the end (throughout, unless startAxis is set)
    int tool = 0;        ///< tool number, a key of the tool table
    bool rapid = false;  ///< G0 / RAPID: still cuts, and any cut is a collision to report
    SourceRef source;
    std::optional<Vec3> startAxis;  ///< the unit axis at the start, when it differs from `axis`
    std::shared_ptr<const RotaryMotion> rotary;  ///< the law of a machine's rotary motion, if any

    Vec3 feed() const { return end - start; }
    /// @brief Whether the tool axis turns during the move (simultaneous multi-axis motion).
    bool turns() const { return startAxis.has_value() || rotary != nullptr; }
};

/// @brief The extent of a move's tip path: its ends where the tip runs straight, else the
/// polyline of tipPath padded by its sag, which holds the curve a machine carries the tip on.
inline Box tipBounds(const Move& m) {
    Box b;
    if (!(m.rotary && m.rotary->tipCarried)) {
        b.expand(m.start);
        b.expand(m.end);
        return b;
    }
    const TipPath path = tipPath(m);
    for (const ToolPose& p : path.poses) b.expand(p.tip);
    return b.padded(path.sag);
}

/// @brief The length of a move's tip path: its chord where the tip runs straight, else tipPath's
/// (short of the curve by at most its lengthError).
inline double tipLength(const Move& m) {
    return m.rotary && m.rotary->tipCarried ? tipPath(m).length : glm::length(m.feed());
}

/// @brief The tool in the spindle changes before move `moveIndex`.
struct ToolChange {
    std::size_t moveIndex = 0;
    int tool = 0;
    SourceRef source;
};

/// @brief A warning or note from a reader or the cutting loop, with its place.
struct Diagnostic {
    enum class Severity { Note, Warning };
    Severity severity = Severity::Warning;
    SourceLocation where;
    std::string message;
};

/// @brief A program turned into moves: the sequence the cutting loop applies in order.
struct ToolPath {
    std::vector<std::string> files;  ///< source files; SourceRef::file indexes this
    std::vector<Move> moves;
    std::vector<ToolChange> toolChanges;

    /// @brief The number every output gives moves[i]: the moves counted from 1 in the order the
    /// program makes them, as a person reads "move 1".
    static std::size_t moveNumber(std::size_t i) { return i + 1; }
    /// @brief "file:line" of a move's source.
    SourceLocation where(const SourceRef& ref) const {
        SourceLocation loc;
        if (ref.file < files.size()) loc.file = files[ref.file];
        loc.line = ref.line;
        return loc;
    }
    /// @brief The extent of the tip's paths (tipBounds), curved ones included.
    Box bounds() const {
        Box b;
        for (const Move& m : moves) b.expand(tipBounds(m));
        return b;
    }
};

/// @brief Tools by number.
using ToolTable = std::map<int, Tool>;

/// @brief A stock size a program states without placing it, such as CAMWorks' APT
/// `INSERT/Stock Size X350. Y150. Z10.5`.
struct StatedStock {
    Vec3 size{0.0};  ///< mm
    SourceLocation where;
};

/// @brief Everything a reader returns.
struct Program {
    ToolPath path;
    ToolTable tools;  ///< tools the program or project defines (APT CUTTER/, .camotics tools)
    std::vector<Diagnostic> diagnostics;
    std::optional<StatedStock> statedStock;  ///< the last one stated
    /// The range (degrees) rotary axes A, B, C take over the moves; empty for an axis never set.
    std::array<Interval, 3> rotaryRanges{Interval::empty(), Interval::empty(), Interval::empty()};
    /// How far the chords of the arcs the readers split (G2/G3, APT CIRCLE) lie from their arcs at
    /// most (mm), and the arc whose chords do; 0 without arcs.
    double arcSag = 0.0;
    SourceRef arcSagSource;
    /// Moves the reader did not put in the path because they run from or to a position the
    /// program does not state (G-code before X, Y and Z are all known, or after a move to an
    /// unstated place): each only sets the position, and a warning says why.
    std::size_t movesNotSimulated = 0;

    /// @brief Runs `next` after this program: its files, moves and tool changes are renumbered
    /// onto the end of these, its tools join these, its diagnostics follow. A number both define
    /// as different tools (two APT files that each load another CUTTER as tool 1) keeps its tool
    /// here, and next's takes a number neither uses, for its own moves, with a note that says so:
    /// no move is cut with the other program's tool.
    void append(Program&& next);
};

/// @brief Where the readers get the text of a file they are told to read (a project's programs,
/// subroutine files, tool tables): returns the file's text, or std::nullopt when there is no such
/// file. An empty FileSource reads the file system. Tests and fuzz targets give a map instead.
using FileSource = std::function<std::optional<std::string>(const std::string& path)>;

}  // namespace dexelmill
