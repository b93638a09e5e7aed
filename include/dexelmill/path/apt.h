/// @file apt.h
/// @brief The APT CL (cutter location) reader for the SolidWorks CAM / CAMWorks / NX style:
/// CUTTER and LOAD/TOOL, GOTO/FROM/GODLTA/RAPID, CIRCLE arcs, MULTAX tool axes, CSYS frames,
/// UNITS, drilling CYCLEs.
///
/// Frames: with `TRNTYP/WORLD` (what SolidWorks CAM writes) GOTO coordinates and axes are in the
/// part frame already and CSYS only gives the default tool axis (its third column) for GOTOs
/// without i,j,k. Without TRNTYP/WORLD, CSYS/r11,r12,r13,t1,r21,...,t3 maps local coordinates to
/// the part frame: p = R p_local + t.
#pragma once

#include <string>
#include <string_view>

#include "dexelmill/path/toolpath.h"

namespace dexelmill {

/// @brief How to read APT CL.
struct AptOptions {
    /// Largest distance between a CIRCLE arc and its chords (mm).
    double chordTolerance = 0.001;
    /// Units before a UNITS statement: false = mm, true = inch.
    bool initialInches = false;
    /// Most chords one arc may become.
    std::size_t maxArcSegments = 1'000'000;
    /// Most moves a program may make before the reader refuses it.
    std::size_t maxMoves = 200'000'000;
    /// What set maxMoves, for the message when a program reaches it (empty: the reader's own
    /// limit). A job sets it to the memory budget that holds that many moves.
    std::string maxMovesReason;
};

/// @brief Interprets APT CL text.
/// @throw ParseError with file:line:col and the offending text.
Program parseApt(std::string_view text, const std::string& fileName,
                 const AptOptions& options = {});

/// @brief Reads and interprets one APT CL file.
/// @throw Error if the file cannot be read; ParseError as parseApt.
Program readApt(const std::string& path, const AptOptions& options = {});

}  // namespace dexelmill
