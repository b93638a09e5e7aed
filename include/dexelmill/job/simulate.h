/// @file simulate.h
/// @brief The main job: program in, part out. Reads the programs (or a CAMotics project), builds
/// the stock, cuts it, rebuilds the level set, meshes it and writes the requested files and a
/// report. The command line's `dexelmill simulate` is a thin layer over this.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dexelmill/compare/deviation.h"
#include "dexelmill/error.h"
#include "dexelmill/geometry/affine.h"
#include "dexelmill/geometry/types.h"
#include "dexelmill/io/atomic_file.h"
#include "dexelmill/job/memory.h"
#include "dexelmill/path/apt.h"
#include "dexelmill/path/gcode.h"
#include "dexelmill/path/toolpath.h"
#include "dexelmill/stock/fine_features.h"
#include "dexelmill/stock/primitive.h"
#include "dexelmill/stock/tridexel.h"
#include "dexelmill/surface/levelset.h"
#include "dexelmill/surface/mesh.h"
#include "dexelmill/sweep/turning.h"
#include "dexelmill/tool/tool.h"

namespace dexelmill {

/// @brief How the part's surface is meshed.
enum class Mesher {
    Dexel,  ///< from the dexels' exact crossings and normals (contourStock)
    Vdb     ///< openvdb::tools::volumeToMesh on the level set alone (meshLevelSet)
};

/// @brief What a simulation reads and writes. Lengths in mm.
struct SimulateOptions {
    /// A `.camotics` project, or one or more programs (G-code or APT CL) run in order, or a
    /// project followed by programs that replace the project's own.
    std::vector<std::string> inputs;
    /// A program already in memory (used instead of `inputs` when set, e.g. by studies).
    std::optional<Program> program;
    /// Where the inputs and the files they name are read from. Empty: the file system.
    FileSource files;

    /// The stock: a box, a cylinder or cone frustum (cast exactly), or a file (STL or VDB)
    /// ray-cast into tri-dexels. With none, the project's workpiece, else the programs' cutting
    /// extent with a margin.
    std::optional<Box> stockBox;
    std::optional<Frustum> stockFrustum;
    std::string stockFile;

    /// Tools by number; they override the project's and the program's own. `defaultTool` serves
    /// every tool number nobody defines (and programs that never select a tool).
    std::map<int, Tool> tools;
    std::optional<Tool> defaultTool;
    /// A LinuxCNC tool table (readToolTable) for the tool numbers that `tools` and the program
    /// leave undefined, before `defaultTool`: each a flat end mill of the table's diameter D, with
    /// a warning, as the table gives no shape. `toolTableUnit`: mm per table unit (25.4 in inches).
    std::string toolTable;
    double toolTableUnit = 1.0;

    /// Lattice spacing; 0 chooses one from the stock (see chooseResolution).
    double resolution = 0.0;
    /// When the spacing is chosen: about this many lattice points along the stock's longest side.
    double cellsAlongLongestSide = 400;
    FamilySet families = FamilySet::all();
    /// Largest distance between an arc and its chords.
    double chordTolerance = 0.001;
    /// The tolerance (mm) of the sweep of a feed move whose tool axis turns (CutOptions).
    double turnTolerance = kDefaultTurnTolerance;
    /// The machine whose rotary axes G-code programs move: a built-in name or a JSON file, read
    /// as the inputs are (machine/kinematics.h); empty for none.
    std::string machine;
    /// Where the machine stands when a G-code program starts (mm, machine coordinates); unset, the
    /// readers wait until the program has set X, Y and Z (GcodeOptions::startPosition).
    std::optional<Vec3> startPosition;
    /// The mesher.
    Mesher mesher = Mesher::Dexel;
    /// Mesh adaptivity in [0, 1]: 0 keeps every cell's vertices; higher values merge flat regions.
    double adaptivity = 0.0;
    /// Rounds of refinement against the exact part (refineMesh); 0 keeps the mesher's mesh. Needs a
    /// box stock: with a file stock it is skipped, with a warning.
    int refineRounds = 0;
    /// Refinement splits an edge whose midpoint lies farther than this many spacings off the exact
    /// part.
    double refineTolerance = 0.002;

    /// The design part (a closed STL in the program's frame), or empty. With it, every move that
    /// removes material the design keeps, deeper than `gougeTolerance` (mm, as distance inside the
    /// design's surface), is reported as a gouge (SimulateReport::gouges).
    std::string designPath;
    /// Places the design in the program's frame when its file is in another.
    std::optional<Affine> designTransform;
    double gougeTolerance = 0.01;
    /// Excess: stock left outside the design farther than this from it (mm) is reported
    /// (SimulateReport::excess...).
    double excessTolerance = 0.05;
    /// A CSV of the gouges, one row per gouging move; needs designPath.
    std::string gougeCsvPath;
    /// A PLY of the machined mesh with each vertex coloured by its signed distance to the design
    /// (deviationColours) and the distance as the property deviation_mm; needs designPath. With a
    /// design, the picture is coloured the same way, with a legend.
    std::string deviationPlyPath;
    /// With a design, the machined surface is measured against it (SimulateReport::
    /// surfaceDeviation) when the picture, the deviation PLY or the report is written, or when
    /// this is set.
    bool measureSurface = false;

    /// Outputs; empty paths are not written. The mesh format follows the extension (.obj, .stl,
    /// .ply).
    std::string meshPath, vdbPath, pngPath, reportPath;

    /// Worker threads for every stage (cutting, rebuilding, meshing, writing); 0 uses every core.
    int threads = 0;

    /// The most memory the job may use (bytes); 0 takes it from the system (memoryBudget). The
    /// job checks the program's moves, the stock and the surface against it before it builds
    /// them, and stops with the figures and a spacing that fits.
    std::size_t maxMemoryBytes = 0;

    /// Called now and then from the calling thread with a stage name and the work done so far
    /// out of `total` (moves while cutting). May be empty.
    std::function<void(const char* stage, std::size_t done, std::size_t total)> progress;
};

/// @brief A collision found while cutting.
struct ReportCollision {
    std::size_t move = 0;  ///< the move's number: the program's moves counted from 1 (ToolPath::moveNumber)
    SourceLocation where;
    /// "rapid" (a rapid move removed material), "shank" (the tool above its cutting length, up to
    /// its holder where it has one, met material) or "holder" (the holder did, withHolder); a move
    /// may have a collision of each kind
    std::string kind;
    double volumeMm3 = 0.0;
};

/// @brief A move that cut into the design (Gouge), with its place and tool.
struct ReportGouge {
    std::size_t move = 0;  ///< the move's number: the program's moves counted from 1 (ToolPath::moveNumber)
    SourceLocation where;
    int tool = 0;
    bool rapid = false;
    double depthMm = 0.0;
    double volumeMm3 = 0.0;
    Vec3 point{0.0};
};

/// @brief A warning or a note from a reader, the job or the cutting loop.
struct ReportWarning {
    SourceLocation where;
    std::string message;
    /// A note tells what the run did in the program's stead (a tool replaced, a subroutine read);
    /// a warning, what it could not honour or what may be wrong.
    Diagnostic::Severity severity = Diagnostic::Severity::Warning;
};

/// @brief Everything the job found; also written as the JSON report.
struct SimulateReport {
    std::string version;
    std::vector<std::string> inputs;
    double resolutionMm = 0.0;
    bool resolutionChosen = false;  ///< true when the job chose the spacing itself
    std::string families;
    Box stockBox;

    std::size_t moves = 0, rapids = 0, toolChanges = 0;
    /// Moves from or to a position the program does not state, which only set it (Program).
    std::size_t movesNotSimulated = 0;
    std::array<int, 3> lattice{0, 0, 0};
    std::array<std::size_t, 3> dexels{0, 0, 0};  ///< per family, 0 when not kept

    double stockVolumeMm3 = 0.0, finalVolumeMm3 = 0.0, removedVolumeMm3 = 0.0;
    std::array<std::optional<double>, 3> familyVolumesMm3;

    std::vector<ReportCollision> collisions;
    std::vector<ReportWarning> warnings;

    /// The design comparison, when a design was given: its file, the tolerance, and the gouges
    /// deepest first.
    std::string designFile;
    /// Whether the design's mesh is closed (checkMesh): where it is open, its solid is a guess.
    bool designClosed = false;
    double gougeToleranceMm = 0.0;
    std::vector<ReportGouge> gouges;
    /// Excess after the cut (findExcess): all the stock outside the design (mm^3), the largest
    /// distance from the design (mm, 0 when none exceeds the tolerance), where, and the regions
    /// thicker than the tolerance, most volume first.
    double excessToleranceMm = 0.0;
    double excessVolumeMm3 = 0.0;
    double excessThicknessMm = 0.0;
    Vec3 excessPoint{0.0};
    struct ExcessRegion {
        Box box;
        double volumeMm3 = 0.0, thicknessMm = 0.0;
        Vec3 point{0.0};
    };
    std::vector<ExcessRegion> excessRegions;
    /// The machined surface against the design (measureDeviation); its per-vertex distances are in
    /// Simulation::deviation, not here.
    std::optional<Deviation> surfaceDeviation;

    /// What the lattice cannot show (finerThanLattice): the mesh leaves that material out and fills
    /// those gaps; the volumes above count both.
    FineFeatures fineFeatures;

    std::string mesher;  ///< "dexel" or "vdb"
    std::size_t meshVertices = 0, meshTriangles = 0;
    bool meshClosed = false;
    std::size_t meshFoldedTriangles = 0;      ///< MeshCheck::foldedTriangles
    std::size_t meshDegenerateTriangles = 0;  ///< MeshCheck::degenerateTriangles
    double meshVolumeMm3 = 0.0;
    /// The dexel mesher's edge crossings: dexel endpoints, and interpolated ones (no dexel along
    /// the edge: a family not kept); its vertices on sharp edges and corners; its cells crossed by
    /// one flat square (two triangles, no vertex).
    std::size_t exactCrossings = 0, interpolatedCrossings = 0, edgeVertices = 0, cornerVertices = 0, plainCells = 0;
    /// Its general path (ContourStats): edges with several crossings meshed and left out (their
    /// cells' triangles folded), the cells round the meshed ones, and the vertices it put on faces.
    std::size_t splitEdges = 0, splitEdgesDropped = 0, splitCells = 0, faceVertices = 0;
    /// Pairs of a cell's patches whose fans pass through each other and could not be set apart
    /// (ContourStats::patchPairsLeftCrossing).
    std::size_t patchPairsLeftCrossing = 0;
    /// Times the dexel mesher meshed the part: one, and one more each time split cells' triangles
    /// folded and their edges were left out.
    int meshRuns = 0;
    /// Refinement (RefineStats): rounds made, vertices and midpoints tested, vertices moved onto
    /// the part (and of them, those moved part of the way), edges split, splits refused,
    /// triangles found passing through another, midpoints without a crossing, vertices and
    /// midpoints moved or split at a nearer crossing along another axis than the nearest to their
    /// normal, short edges collapsed.
    int refineRounds = 0;
    std::size_t refineQueries = 0, refineSnapped = 0, refineSnapPartial = 0, refineSplit = 0,
                refineRefused = 0, refineCrossed = 0, refineNoCrossing = 0, refineLaterAxis = 0,
                refineCollapsed = 0;

    struct Timing {
        double parse = 0, design = 0, cut = 0, rebuild = 0, mesh = 0, refine = 0, write = 0, total = 0;
    } timingS;
    double peakMemoryMb = 0.0;
    /// Whether malloc's heap asks for transparent huge pages (heapOnHugePages).
    bool heapOnHugePages = false;
    /// Threads the process started while the job ran: TBB's workers, which start only when a
    /// stage's arena asks for them. In a fresh process with `threads` = N, at most N - 1; 0 when
    /// an earlier job in the same process already started them.
    std::size_t threadsStarted = 0;
    std::size_t stockMemoryBytes = 0;
};

/// @brief Everything one run produced, in memory.
struct Simulation {
    Program program;
    ToolTable tools;  ///< the tools the moves used, after the command line's overrides
    std::optional<TriDexelStock> stock;
    LevelSet levelSet;
    Mesh mesh;
    /// With a design: each mesh vertex's signed distance to it (Deviation::distance, mm).
    std::vector<double> deviation;
    SimulateReport report;
};

/// @brief Reads, cuts, rebuilds and meshes; writes no file (the report's write and total times
/// are then incomplete).
/// @throw Error (ParseError with a location for bad programs) on any input or processing error.
Simulation runSimulation(const SimulateOptions& options);

/// @brief The tool a job cuts a tool number nothing defines with, when no --tool without a number
/// (SimulateOptions::defaultTool) is given: the only tool of `defined` (the program's tools and
/// the command line's) when it holds exactly one, with a warning; otherwise none, and the job
/// stops with an error naming the number. `info` tells the same.
std::optional<int> standInTool(const ToolTable& defined);

/// @brief How a job reads G-code: the chord tolerance, the reader's own limits, and no more
/// moves than `budget` holds. `simulate`, `info` and the fuzz targets all read with these.
GcodeOptions jobGcodeOptions(double chordTolerance, const MemoryBudget& budget);
/// @brief The same for APT CL.
AptOptions jobAptOptions(double chordTolerance, const MemoryBudget& budget);

/// @brief Runs the whole job: runSimulation, then writes the requested files.
/// @throw Error as runSimulation, or when a file cannot be written; no output file is then left
/// half-written, and no existing file is replaced: the files are renamed together once all are
/// written (OutputBatch).
SimulateReport simulate(const SimulateOptions& options);

/// @brief The files the job reads that the options name, each with its option: the programs or
/// project (INPUTS; none for a program in memory), the --stock, --design and --machine files
/// (not a built-in machine's name). Outputs that are one of them are refused (checkSeparateFiles).
std::vector<NamedFile> jobInputFiles(const SimulateOptions& options);

/// @brief The report as JSON text (the fields of SimulateReport, snake_case, units in the names).
std::string reportJson(const SimulateReport& report);

/// @brief The gouges as CSV text: a header row, then one row per gouging move, deepest first:
/// move (0-based), file, line, tool, depth_mm, volume_mm3, x, y, z (the deepest point, mm), rapid
/// (1 for a rapid move). Text fields are quoted.
std::string gougeCsv(const SimulateReport& report);

/// @brief The fewest lattice cells a spacing may leave across the stock's thinnest side: coarser,
/// the lattice rounds the stock up to whole cells of more material than it has, and the level set
/// has no inside to mesh. A job given a coarser spacing stops with an error naming the largest.
constexpr int kMinCellsAcross = 2;

/// @brief A default lattice spacing for a stock box: its longest side divided by `cells` (about),
/// but no more than the thinnest side over kMinCellsAcross, rounded down to 1, 2 or 5 times a
/// power of ten.
double chooseResolution(const Box& stock, double cells = 400);

}  // namespace dexelmill
