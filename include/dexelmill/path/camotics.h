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

/// @brief The stock of a CAMotics project. The defaults are CAMotics' own, for a project that
/// leaves the workpiece or one of its entries out: automatic, with a 5 % margin.
struct ProjectWorkpiece {
    /// Bounds derived from the tool path (CAMotics "automatic"); `bounds` then holds the last
    /// bounds CAMotics saved, and automaticWorkpieceBounds() recomputes them.
    bool automatic = true;
    /// Margin of automatic bounds, in percent of each dimension (CAMotics convention).
    double marginPercent = 5.0;
    Box bounds;  ///< mm
};

/// @brief How a CAMotics project chooses its resolution: the number it stores (manual), or one
/// computed from the workpiece's volume (projectResolution).
enum class ResolutionMode { Manual, Low, Medium, High, VeryHigh };

/// @brief CAMotics' resolution (mm) for a mode other than manual: the cube root of the
/// workpiece's volume over 1e5 (low), 2.5e5 (medium), 5e6 (high) or 1e7 (very high) cells. Bear
/// (80 x 80 x 20 mm, high) gets 0.294723 mm, the number CAMotics saved in it.
double projectResolution(ResolutionMode mode, const Box& workpiece);

/// @brief A program a project runs.
struct ProjectFile {
    std::string path;      ///< resolved relative to the project
    SourceLocation entry;  ///< the project's entry that names it; no line for a program given in its place
};

/// @brief A CAMotics project.
struct Project {
    std::string file;              ///< the project file
    /// Project units. CAMotics shows lengths in them but stores the workpiece and the resolution
    /// in mm, and its G-code starts in mm (G21) whatever they are: only a tool's own units scale
    /// its sizes.
    bool metric = true;
    ToolTable tools;               ///< tools by number, mm
    ProjectWorkpiece workpiece;
    std::vector<ProjectFile> files;  ///< the programs, in the order they run
    /// CAMotics' default when the project names none: medium.
    ResolutionMode resolutionMode = ResolutionMode::Medium;
    /// The resolution as written (mm), which only the manual mode uses; 0 when absent or not
    /// positive.
    double resolution = 0.0;
    /// The resolution as written when it is not positive (mm): the job chooses one and says so.
    std::optional<double> unusableResolution;
    std::vector<Diagnostic> diagnostics;
};

/// @brief Parses a `.camotics` project (JSON; `//` and `/* */` comments allowed).
/// Tool shapes: cylindrical -> flat end mill, ballnose -> ball end mill, conical -> V-bit whose
/// cone reaches the diameter at the tool length, snubnose -> taper from snub_diameter at the tip
/// to diameter at the tool length (a snub as wide as the tool is a flat end mill, and none a
/// V-bit), in any case of letters, and `cylinder` and `cone` as CAMotics' other names for the
/// first and third. A tool's imperial lengths are converted to mm.
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
/// @throw ParseError at a program's entry in the project (Error for a program given in its place)
/// when the program is missing, cannot be read or its name says it holds a solid (as readProgram);
/// ParseError for malformed input.
Program runProject(const Project& project, const GcodeOptions& options = {});

/// @brief CAMotics' automatic workpiece: the box of the cutting moves, widened by the cutting
/// radius of each move's tool across its axis (the widest defined tool for tools nobody defined),
/// with its top at z = 0 and its bottom at the lowest cut, or kMinAutomaticThickness below that
/// cut where the block would be thinner than that, then grown by marginPercent of each size (not
/// above the top).
/// Empty when no cutting move has a tool.
Box automaticWorkpieceBounds(const Program& program, double marginPercent);
/// @brief The same for a tool path and the tools its moves use.
Box automaticWorkpieceBounds(const ToolPath& path, const ToolTable& tools, double marginPercent);

/// @brief The least thickness of CAMotics' automatic workpiece (mm): a block from the lowest cut
/// up to z = 0 that is thinner gets this much more stock below that cut.
constexpr double kMinAutomaticThickness = 2.0;

/// @brief The box of the cutting moves, widened by each move's tool radius across its axis as in
/// automaticWorkpieceBounds, without CAMotics' rules for the top: where a program's own cuts lie.
Box cuttingBounds(const ToolPath& path, const ToolTable& tools);

/// @brief Kinds of program files.
enum class ProgramKind { Gcode, Apt, Camotics };

/// @brief The kind of a file: by extension (.camotics; .apt .cl .cls .aptsource; .nc .ngc .gcode
/// .tap .cnc ...), else by content (APT statements look like `WORD/...`).
ProgramKind detectProgramKind(const std::string& path, std::string_view text);

/// @brief Reads any program file: G-code, APT CL, or a CAMotics project (whose programs run in
/// order with the project's tools). Files are read from `gcode.files`.
/// @throw Error if the file cannot be read, or its name says it holds a solid (.stl, .obj, .ply or
/// .vdb, any case), which is not read; ParseError for malformed input.
Program readProgram(const std::string& path, const GcodeOptions& gcode = {},
                    const AptOptions& apt = {});

}  // namespace dexelmill
