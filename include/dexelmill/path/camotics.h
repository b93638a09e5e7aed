/// @file camotics.h
/// @brief CAMotics project files (`.camotics`, JSON): tools, workpiece, program files,
/// resolution; and readProgram, which opens any program file by its kind.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/path/apt.h"
#include "dexelmill/path/gcode.h"
#include "dexelmill/path/toolpath.h"

namespace dexelmill {

/// @brief The stock of a CAMotics project.
struct ProjectWorkpiece {
    /// Bounds derived from the tool path (CAMotics "automatic"); `bounds` then holds the last
    /// bounds CAMotics saved, and automaticWorkpieceBounds() recomputes them.
    bool automatic = false;
    /// Margin of automatic bounds, in percent of each dimension (CAMotics convention).
    double marginPercent = 0.0;
    Box bounds;  ///< mm
};

/// @brief A CAMotics project.
struct Project {
    std::string file;              ///< the project file
    bool metric = true;            ///< project units; also the initial units of its G-code
    ToolTable tools;               ///< tools by number, mm
    ProjectWorkpiece workpiece;
    std::vector<std::string> files;  ///< program files, resolved relative to the project
    double resolution = 0.0;       ///< mm; 0 when absent or not positive
    /// The resolution as written when it is not positive (mm): the job chooses one and says so.
    std::optional<double> unusableResolution;
    std::string resolutionMode;    ///< "low", "medium", "high", "manual"... as written
    std::vector<Diagnostic> diagnostics;
};

/// @brief Parses a `.camotics` project (JSON; `//` and `/* */` comments allowed).
/// Tool shapes: cylindrical -> flat end mill, ballnose -> ball end mill, conical -> V-bit whose
/// cone reaches the diameter at the tool length, snubnose -> taper from snub_diameter at the tip
/// to diameter at the tool length. Imperial lengths are converted to mm.
/// @param directory folder that relative program file names are resolved against
/// @throw ParseError for invalid JSON or fields of the wrong type or value.
Project parseCamoticsProject(std::string_view text, const std::string& fileName,
                             const std::string& directory);

/// @brief Reads a `.camotics` project file, from `files` when it is given.
/// @throw Error if the file cannot be read; ParseError as parseCamoticsProject.
Project readCamoticsProject(const std::string& path, const FileSource& files = {});

/// @brief Runs a project's programs in order (T changes the tool, as in CAMotics), read from
/// `options.files`, and returns
/// them as one program whose tools are the project's tools. Tools the programs call but the
/// project does not define give a warning.
Program runProject(const Project& project, const GcodeOptions& options = {});

/// @brief CAMotics-style automatic workpiece: the box of the cutting moves, widened by the
/// cutting radius of each move's tool across its axis (the widest defined tool for tools nobody
/// defined), topped at z = 0 when the cuts go below it, and grown by marginPercent of each size
/// (not above the top).
Box automaticWorkpieceBounds(const Program& program, double marginPercent);
/// @brief The same for a tool path and the tools its moves use.
Box automaticWorkpieceBounds(const ToolPath& path, const ToolTable& tools, double marginPercent);

/// @brief Kinds of program files.
enum class ProgramKind { Gcode, Apt, Camotics };

/// @brief The kind of a file: by extension (.camotics; .apt .cl .cls .aptsource; .nc .ngc .gcode
/// .tap .cnc ...), else by content (APT statements look like `WORD/...`).
ProgramKind detectProgramKind(const std::string& path, std::string_view text);

/// @brief Reads any program file: G-code, APT CL, or a CAMotics project (whose programs run in
/// order with the project's tools). Files are read from `gcode.files`.
/// @throw Error if the file cannot be read; ParseError for malformed input.
Program readProgram(const std::string& path, const GcodeOptions& gcode = {},
                    const AptOptions& apt = {});

}  // namespace dexelmill
