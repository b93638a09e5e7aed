/// @file gcode.h
/// @brief The RS274/NGC (G-code) reader: LinuxCNC's dialect plus the Fanuc, Haas and GRBL forms
/// met in practice. Programs are interpreted (parameters, expressions, O-word flow, M98
/// subprograms, canned cycles) into linear cutter-location moves; arcs and helices are split into
/// chords within a tolerance.
///
/// Coordinates of the moves are machine coordinates in mm: the program point plus the active work
/// offsets (G54..G59.3, G92, G52), after the tilted work plane (G68.2) if one is active. Tool
/// length offsets do not move the cutter-location point: the tip follows the programmed point.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/machine/kinematics.h"
#include "dexelmill/path/toolpath.h"

namespace dexelmill {

/// @brief How to read G-code.
struct GcodeOptions {
    /// Largest distance between an arc and the chords that replace it (mm).
    double chordTolerance = 0.001;
    /// Units before the program says G20/G21: false = mm (G21), true = inch (G20).
    bool initialInches = false;
    /// Tool axis of the moves while no tilted work plane is active (normalised by the reader).
    Vec3 initialToolAxis{0.0, 0.0, 1.0};
    /// A `T` word changes the tool at once, without M6 (CAMotics behaviour). Off: T only selects,
    /// M6 changes (LinuxCNC behaviour).
    bool toolChangeOnT = false;
    /// Run blocks starting with `/` (block delete switch off). Off: skip them.
    bool runDeletedBlocks = true;
    /// Deepest nesting of subroutine calls before the program is declared runaway recursion.
    int maxCallDepth = 64;
    /// Most blocks executed (loops included) before the program is declared not to terminate.
    std::size_t maxBlocks = 50'000'000;
    /// Most chords one arc may become before the reader refuses it.
    std::size_t maxArcSegments = 1'000'000;
    /// Most moves a program may make (loops and repeats included) before the reader refuses it.
    std::size_t maxMoves = 200'000'000;
    /// What set maxMoves, for the message when a program reaches it (empty: the reader's own
    /// limit). A job sets it to the memory budget that holds that many moves.
    std::string maxMovesReason;
    /// Where the machine is when the program starts (machine coordinates, mm). Unset, the start
    /// is unknown: moves only establish the position until X, Y and Z have all been programmed,
    /// so no move sweeps from a guessed origin through the stock (one warning says so). LinuxCNC
    /// itself starts wherever the machine is, commonly (0, 0, 0).
    std::optional<Vec3> startPosition;
    /// The machine whose rotary axes A, B, C the program moves (machine/kinematics.h). Without
    /// one, a block that turns a rotary axis is an error that names --machine.
    std::optional<Machine> machine;
    /// Where named files are read from: the tool table, subroutine files, the files of
    /// readGcodeFiles and of a project (runProject). Empty: the file system.
    FileSource files;
};

/// @brief Interprets G-code text.
/// @param text the program
/// @param fileName the name used in locations and in ToolPath::files
/// @throw ParseError with file:line:col and the offending text for malformed input or
/// unsupported motion (rotary axes, XY rotation, threading, probing...).
Program parseGcode(std::string_view text, const std::string& fileName,
                   const GcodeOptions& options = {});

/// @brief Reads and interprets one G-code file.
/// @throw Error if the file cannot be read; ParseError as parseGcode.
Program readGcode(const std::string& path, const GcodeOptions& options = {});

/// @brief Runs several G-code files one after the other on one machine (state such as position,
/// tool and offsets carries over), as CAMotics does with a project's file list.
/// @throw Error if a file cannot be read; ParseError as parseGcode.
Program readGcodeFiles(const std::vector<std::string>& paths, const GcodeOptions& options = {});

}  // namespace dexelmill
