#include "dexelmill/job/simulate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include <glm/trigonometric.hpp>
#include <tbb/task_arena.h>

#include "dexelmill/compare/design.h"
#include "dexelmill/compare/excess.h"
#include "dexelmill/decimal.h"
#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"
#include "dexelmill/io/atomic_file.h"
#include "dexelmill/io/file_name.h"
#include "dexelmill/io/mesh_io.h"
#include "dexelmill/io/picture.h"
#include "dexelmill/io/stock_io.h"
#include "dexelmill/io/vdb_io.h"
#include "dexelmill/job/memory.h"
#include "dexelmill/machine/kinematics.h"
#include "dexelmill/path/camotics.h"
#include "dexelmill/refine/refine.h"
#include "dexelmill/stock/cut.h"
#include "dexelmill/stock/fine_features.h"
#include "dexelmill/sweep/turning.h"
#include "dexelmill/surface/contour.h"
#include "dexelmill/surface/levelset.h"
#include "dexelmill/surface/voxelize.h"
#include "job/detail/deviation_files.h"
#include "job/detail/tools.h"

namespace dexelmill {

namespace {

using Clock = std::chrono::steady_clock;

/// The margin (percent of each size) of the stock guessed from a program's cuts.
constexpr double kGuessMarginPercent = 5.0;

/// How far (relative) a project's stored resolution may lie from the one its mode computes before
/// the job says which it took: CAMotics saves 6 significant digits.
constexpr double kStoredResolutionSlack = 1e-5;

double seconds(Clock::time_point since) {
    return std::chrono::duration<double>(Clock::now() - since).count();
}

/// Whether the part's surface is measured against the design: when an output shows it. It costs
/// about 0.6 us per vertex on one thread (basemach).
bool measuresSurface(const SimulateOptions& o) {
    return o.measureSurface || !o.pngPath.empty() || !o.deviationPlyPath.empty() || !o.reportPath.empty();
}

/// The format the mesh is written in: its name's extension, or binary STL for a target written in
/// place (a device, a FIFO, /dev/stdout) whose name is not .obj or .ply.
std::string meshFormat(const std::string& path) {
    const std::string e = lowerExtension(path);
    return e != ".obj" && e != ".ply" && writtenInPlace(path) ? ".stl" : e;
}

/// Fails before any work when an output names a format we cannot write, cannot be written, or would
/// overwrite an input or another output.
void checkOutputs(const SimulateOptions& o) {
    if (!o.meshPath.empty()) {
        const std::string e = meshFormat(o.meshPath);
        if (e != ".obj" && e != ".stl" && e != ".ply")
            throw Error("output '" + o.meshPath + "': the mesh format follows the extension: .obj, .stl or .ply");
    }
    if (!o.vdbPath.empty() && !takesFormat(o.vdbPath, ".vdb"))
        throw Error("output '" + o.vdbPath + "': a level set is written as .vdb");
    if (!o.pngPath.empty() && !takesFormat(o.pngPath, ".png"))
        throw Error("output '" + o.pngPath + "': a picture is written as .png");
    if (!o.reportPath.empty() && !takesFormat(o.reportPath, ".json"))
        throw Error("output '" + o.reportPath + "': the report is written as .json");
    if (!o.gougeCsvPath.empty() && o.designPath.empty())
        throw Error("output '" + o.gougeCsvPath + "': gouges are found against a design: give --design PART.stl");
    if (!o.deviationPlyPath.empty() && o.designPath.empty())
        throw Error("output '" + o.deviationPlyPath + "': the deviation is measured against a design: give --design PART.stl");
    if (!o.deviationPlyPath.empty() && !takesFormat(o.deviationPlyPath, ".ply"))
        throw Error("output '" + o.deviationPlyPath + "': the deviation mesh is written as .ply");
    if (!o.gougeCsvPath.empty() && !takesFormat(o.gougeCsvPath, ".csv"))
        throw Error("output '" + o.gougeCsvPath + "': the gouges are written as .csv");
    if (!(o.gougeTolerance >= 0.0) || !std::isfinite(o.gougeTolerance))
        throw Error("the gouge tolerance must be a finite distance of 0 mm or more");
    checkSeparateFiles(jobInputFiles(o), {{"-o", o.meshPath},
                                          {"--vdb", o.vdbPath},
                                          {"--png", o.pngPath},
                                          {"--gouge-csv", o.gougeCsvPath},
                                          {"--deviation-ply", o.deviationPlyPath},
                                          {"--report", o.reportPath}});
    // A folder that is missing or not writable is found now, not after the cut.
    for (const std::string* path : {&o.meshPath, &o.vdbPath, &o.pngPath, &o.gougeCsvPath, &o.deviationPlyPath, &o.reportPath})
        if (!path->empty()) checkWritable(*path);
    if (!(o.excessTolerance >= 0.0) || !std::isfinite(o.excessTolerance))
        throw Error("the excess tolerance must be a finite distance of 0 mm or more");
}

/// Warns of what the lattice cannot show (finerThanLattice): material the surface leaves out, and
/// gaps it fills, with their share of the part's volume (`part`, mm^3). The dexels keep both, so
/// the volumes reported count them.
void noteFineFeatures(const FineFeatures& f, double h, double part, Mesher mesher,
                      std::vector<ReportWarning>& jobWarnings) {
    const auto note = [&](const FineStretches& s, const char* what) {
        if (s.count == 0) return;
        const FineRegion& most = s.regions.front();
        char text[800];
        std::snprintf(text, sizeof text,
                      "%s %zu dexel stretch%s with no lattice point in them (spacing %.4g mm), in %zu place%s, about "
                      "%s in all (%.2g %% of the part); the most, %s, within (%.3f, %.3f, %.3f)-(%.3f, "
                      "%.3f, %.3f), up to %.3g mm across at (%.3f, %.3f, %.3f); the volumes count them, a finer "
                      "--resolution shows them",
                      what, s.count, s.count == 1 ? "" : "es", h, s.regionCount, s.regionCount == 1 ? "" : "s",
                      volumeText(s.volumeMm3).c_str(), part > 0.0 ? 100.0 * s.volumeMm3 / part : 0.0,
                      volumeText(most.volumeMm3).c_str(), most.box.lo.x,
                      most.box.lo.y, most.box.lo.z, most.box.hi.x, most.box.hi.y, most.box.hi.z, most.widestMm,
                      most.widestAt.x, most.widestAt.y, most.widestAt.z);
        ReportWarning w;
        w.message = text;
        jobWarnings.push_back(w);
    };
    // The dexel mesher meshes what the dexels cross of them (contour.h); the level set, and with
    // it the picture, the .vdb and the vdb mesher, cannot.
    if (mesher == Mesher::Dexel) {
        note(f.material, "material thinner than the lattice (walls, fins, ridge tops) is left out of the level set, and "
                         "so of the picture and the .vdb; the mesh shows it where the dexels cross it:");
        note(f.gaps, "gaps narrower than the lattice (slots, grooves) are filled in the level set, and so in the picture "
                     "and the .vdb; the mesh shows them where the dexels cross them:");
        return;
    }
    note(f.material, "material thinner than the lattice (walls, fins, ridge tops) is left out of the level set and the "
                     "mesh (refinement restores only what the mesh passes near):");
    note(f.gaps, "gaps narrower than the lattice (slots, grooves) are filled in the level set and the mesh:");
}

/// How far (relative to the largest coordinate, at least 1 mm) a design may reach past the stock's
/// box before the job says so: an STL stores float coordinates, which round by half of 2^-23
/// relative, so a design face on a stock face may lie that far out.
constexpr double kDesignBeyondStockSlack = 0x1p-23;

/// Warns when the design reaches past a stock the user gave (`stock`, its box): there the part
/// cannot hold the design, and the cut there is not compared, since no material is.
void noteDesignBeyondStock(const Box& design, const Box& stock, const std::string& designPath,
                           std::vector<ReportWarning>& jobWarnings) {
    const char* sides[3][2] = {{"-x", "+x"}, {"-y", "+y"}, {"-z", "+z"}};
    std::string beyond;
    for (int i = 0; i < 3; ++i) {
        const double scale =
            std::max({1.0, std::abs(design.lo[i]), std::abs(design.hi[i]), std::abs(stock.lo[i]), std::abs(stock.hi[i])});
        const double slack = kDesignBeyondStockSlack * scale;
        const double out[2] = {stock.lo[i] - design.lo[i], design.hi[i] - stock.hi[i]};
        for (int s = 0; s < 2; ++s) {
            if (!(out[s] > slack)) continue;
            char text[80];
            std::snprintf(text, sizeof text, "%s%.4g mm on %s", beyond.empty() ? "" : ", ", out[s], sides[i][s]);
            beyond += text;
        }
    }
    if (beyond.empty()) return;
    char text[400];
    std::snprintf(text, sizeof text,
                  "the design reaches past the stock's box (%s): its box is (%.4f, %.4f, %.4f)-(%.4f, %.4f, %.4f), "
                  "the stock's (%.4f, %.4f, %.4f)-(%.4f, %.4f, %.4f); the part cannot hold the design there",
                  beyond.c_str(), design.lo.x, design.lo.y, design.lo.z, design.hi.x, design.hi.y, design.hi.z,
                  stock.lo.x, stock.lo.y, stock.lo.z, stock.hi.x, stock.hi.y, stock.hi.z);
    ReportWarning w;
    w.where.file = designPath;
    w.message = std::string(text) + "; check --stock and --design-transform";
    jobWarnings.push_back(w);
}

/// Warns when the chords the readers cut arcs into lie farther from their arcs than the lattice
/// spacing `h`: the part then shows the chords' facets, which the lattice resolves, where the
/// program asked for arcs.
void noteArcChords(const Program& program, double h, double chordTolerance,
                   std::vector<ReportWarning>& jobWarnings) {
    if (!(program.arcSag > h)) return;
    char text[400];
    std::snprintf(text, sizeof text,
                  "arcs are cut as chords that lie up to %.4g mm from their arcs (--chord-tolerance %g mm), more "
                  "than the lattice spacing of %g mm: where they cut, the part shows their facets; a --chord-tolerance of "
                  "%g mm or less keeps them within the spacing",
                  program.arcSag, chordTolerance, h, h);
    const SourceLocation at = program.path.where(program.arcSagSource);
    ReportWarning w;
    w.where = at;
    w.message = text;
    jobWarnings.push_back(w);
}

/// Moves whose tool axis turns. A feed move is swept turning (TurningSweep, within the job's
/// turn tolerance); the readers have refused opposite axes, which no one great circle joins. A rapid
/// that turns is a reorientation whose path is the machine's, not the program's straight line: it
/// is swept with its end axis, with a warning where it can reach the stock; a rapid of a machine's
/// rotary axes follows the machine's law (Move::rotary) and needs no warning.
void checkTurningMoves(const ToolPath& path, const ToolTable& tools, const Box& stockBox,
                       std::vector<ReportWarning>& jobWarnings) {
    std::size_t rapids = 0;
    SourceLocation firstRapid;
    for (const Move& m : path.moves) {
        // A machine's rotary move has a known law, swept as it is (sweepsTurning): no great circle
        // to check and, at rapid, no end axis to warn of.
        if (!m.turns() || m.rotary) continue;
        // The readers refuse opposite axes (APT's emit), so the great circle exists.
        const Box reach = turningMoveBox(m, ToolReach(tools.at(m.tool)));
        if (m.rapid && reach.overlaps(stockBox) && rapids++ == 0) firstRapid = path.where(m.source);
    }
    if (rapids == 0) return;
    ReportWarning w;
    w.where = firstRapid;
    w.message = std::to_string(rapids) + (rapids == 1 ? " move turns" : " moves turn") +
                " the tool axis at rapid within reach of the stock (the first here): each is swept with its end axis "
                "throughout, while the machine's own path for the turn decides where the tool really goes";
    jobWarnings.push_back(w);
}

struct LoadedStock {
    TriDexelStock stock;
    Box box;
    bool isBox = true;  ///< the stock is the box itself (not a file cast into the lattice)
    bool aroundDesign = false;  ///< the box was made around the design (no stock given)
};

/// A stock box from the program when none is given. For a project, CAMotics' automatic workpiece
/// with its margin. For a program, its cutting moves' extent, topped at z = 0 where the cuts go
/// below it, grown by kGuessMarginPercent of each size (not above the top). Else every move's
/// extent; an axis the program never moves along gets a thickness of 5 % of the largest extent (at
/// least 1 mm) on both sides. `cutTop` is the cuts' own top where the box was topped at z = 0 below
/// it, else NaN. Empty when the program makes no moves.
Box guessStock(const ToolPath& path, const ToolTable& tools, const Project* project, double& cutTop) {
    cutTop = std::numeric_limits<double>::quiet_NaN();
    Box box;
    if (project) {
        box = automaticWorkpieceBounds(path, tools, project->workpiece.marginPercent);
    } else {
        box = cuttingBounds(path, tools);
        if (!box.isEmpty()) {
            if (box.lo.z < 0.0 && box.hi.z > 0.0) cutTop = box.hi.z, box.hi.z = 0.0;
            const Vec3 margin = box.size() * (kGuessMarginPercent / 100.0);
            box.lo -= margin;
            box.hi.x += margin.x;
            box.hi.y += margin.y;
        }
    }
    if (box.isEmpty()) {
        box = path.bounds();
        double widest = 0.0;
        for (const auto& [n, t] : tools) widest = std::max(widest, t.cuttingRadius());
        box = box.padded(widest);
    }
    if (box.isEmpty()) return box;
    const Vec3 size = box.size();
    const double pad = std::max(1.0, 0.05 * std::max({size.x, size.y, size.z}));
    for (int a = 0; a < 3; ++a) {
        if (size[a] > tol::kLength) continue;
        box.lo[a] -= pad;
        box.hi[a] += pad;
    }
    return box;
}

LoadedStock loadStock(const SimulateOptions& o, const MemoryBudget& budget, const Program& program,
                      const ToolTable& tools, const Project* project, const Mesh* design,
                      SimulateReport& report, std::vector<ReportWarning>& jobWarnings) {
    Box box;
    bool aroundDesign = false;
    std::optional<LevelSet> fromVdb;
    std::optional<Mesh> fromStl;
    if (o.stockBox) {
        box = *o.stockBox;
    } else if (o.stockFrustum) {
        box = o.stockFrustum->bounds();
    } else if (!o.stockFile.empty()) {
        const std::string e = lowerExtension(o.stockFile);
        if (e == ".stl") {
            fromStl = readStl(o.stockFile);
            box = fromStl->bounds();
        } else if (e == ".vdb") {
            fromVdb = readVdb(o.stockFile);
            box = materialBounds(*fromVdb);
        } else {
            throw Error("stock '" + o.stockFile +
                        "': expected box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX, cylinder:AXIS,X,Y,Z,R,H, "
                        "cone:AXIS,X,Y,Z,R0,R1,H, a FILE.stl or a FILE.vdb");
        }
        if (box.isEmpty()) throw Error("stock '" + o.stockFile + "' holds no material");
    } else if (project && !project->workpiece.automatic && !project->workpiece.bounds.isEmpty()) {
        box = project->workpiece.bounds;
    } else if (design) {
        ReportWarning w;
        box = designStockBox(design->bounds(), program.statedStock, w.message);
        aroundDesign = true;
        jobWarnings.push_back(w);
    } else {
        double cutTop = 0.0;
        box = guessStock(program.path, tools, project, cutTop);
        if (box.isEmpty()) {
            // The job ends here, before the report that would carry the reader's warnings. The
            // first about a position the reader does not know says why no move was made (moves
            // from an unknown start only set the position); else the first warning is given.
            // Where the start position is what the program never gives, --start gives it, and the
            // stock can then be guessed.
            const auto says = [](const Diagnostic& d, const char* what) {
                return d.severity == Diagnostic::Severity::Warning && d.message.find(what) != std::string::npos;
            };
            const Diagnostic* why = nullptr;
            for (const char* what : {"start position", "unknown", ""}) {
                for (const Diagnostic& d : program.diagnostics)
                    if (!why && says(d, what)) why = &d;
            }
            const bool unknownStart = why && says(*why, "start position");
            std::string message = "no stock given and the program has no moves to guess one from; use --stock";
            if (unknownStart)
                message = "no stock given and the program has no moves to guess one from, as it never gives the "
                          "position it starts from; use --start X,Y,Z (where the machine stands at its start), or "
                          "--stock";
            if (why) message += " (the program's warning: " + why->where.str() + ": " + why->message + ")";
            throw Error(message);
        }
        if (!project) {
            ReportWarning w;
            char extent[300];
            std::snprintf(extent, sizeof extent, "no --stock given: using the program's cutting extent plus %g %%",
                          kGuessMarginPercent);
            w.message = extent;
            if (std::isfinite(cutTop)) {
                std::snprintf(extent, sizeof extent,
                              ", its top at z = 0 mm, where the program's cuts go down from: the cuts above it, up "
                              "to z = %.4g mm, meet no stock; --stock gives a taller one",
                              cutTop);
                w.message += extent;
            }
            if (program.statedStock) {
                const StatedStock& st = *program.statedStock;
                char text[200];
                std::snprintf(text, sizeof text, "; the program states a %g x %g x %g mm stock (%s:%d) without "
                              "placing it: --design PART.stl places it around the design", st.size.x, st.size.y,
                              st.size.z, st.where.file.c_str(), st.where.line);
                w.message += text;
            }
            jobWarnings.push_back(w);
        }
    }
    const Vec3 size = box.size();
    if (!(size.x > 0 && size.y > 0 && size.z > 0)) throw Error("the stock box has no volume");

    double h = o.resolution;
    if (h <= 0 && project) {
        if (project->resolutionMode != ResolutionMode::Manual) {
            // CAMotics computes the resolution from the workpiece; the number stored beside the
            // mode is only the manual mode's, and may be older than the workpiece.
            h = projectResolution(project->resolutionMode, box);
            if (project->resolution > 0 && std::abs(h - project->resolution) > kStoredResolutionSlack * h) {
                ReportWarning w;
                w.where.file = project->file;
                char text[240];
                std::snprintf(text, sizeof text,
                              "the project's resolution mode computes %g mm from the stock, as CAMotics does; "
                              "its stored resolution %g mm applies in the manual mode only",
                              h, project->resolution);
                w.message = text;
                jobWarnings.push_back(w);
            }
        } else if (project->resolution > 0) {
            h = project->resolution;
        }
    }
    if (h <= 0) {
        h = chooseResolution(box, o.cellsAlongLongestSide);
        report.resolutionChosen = true;
        if (project && project->unusableResolution) {
            ReportWarning w;
            w.where.file = project->file;
            char text[160];
            std::snprintf(text, sizeof text, "project resolution %g mm is not positive: using %g mm, chosen from the stock",
                          *project->unusableResolution, h);
            w.message = text;
            jobWarnings.push_back(w);
        }
    }
    // kMinCellsAcross (a 20 x 16 x 5 mm block at 10 mm gave an empty mesh and a part of 2,000 mm^3).
    const int thin = size.x <= size.y && size.x <= size.z ? 0 : (size.y <= size.z ? 1 : 2);
    if (size[thin] < kMinCellsAcross * h) {
        char text[300];
        std::snprintf(text, sizeof text,
                      "a spacing of %g mm is too coarse for this %g x %g x %g mm stock: the lattice needs %d cells "
                      "across its thinnest side (%g mm along %c); give --resolution %g mm or less",
                      h, size.x, size.y, size.z, kMinCellsAcross, size[thin], "xyz"[thin], size[thin] / kMinCellsAcross);
        throw Error(text);
    }
    // A stock file takes the lattice readStock gives it: one whose lines miss an STL's faces at
    // round coordinates, or the one a VDB of dexelmill's records at its own spacing (a line on
    // the box's faces there would lose the outer ring of dexels).
    const Lattice lattice = fromStl   ? stockLattice(*fromStl, h)
                            : fromVdb ? stockLattice(*fromVdb, h)
                                      : Lattice::fromBox(box, h);
    // The stock's dexels (and the design's, cast on the same lattice) and, at the least, the level
    // set and mesh of the block's own faces.
    const double dexels = (design ? 2.0 : 1.0) * stockBytes(lattice, o.families);
    const double faces = kSurfaceBytesPerCrossing * boxCrossings(lattice);
    const double base = double(bytesInUse(budget));
    if (base + dexels + faces > double(budget.bytes)) {
        char text[512];
        std::snprintf(text, sizeof text,
                      "a spacing of %g mm on this %g x %g x %g mm stock needs about %s (its dexels%s %s, the level "
                      "set and mesh of the block's faces alone %s), more than the %s this job may use (%s); a "
                      "spacing of %g mm or more fits%s",
                      h, size.x, size.y, size.z, formatBytes(base + dexels + faces).c_str(),
                      design ? " and the design's" : "", formatBytes(dexels).c_str(), formatBytes(faces).c_str(), formatBytes(double(budget.bytes)).c_str(),
                      budget.source.c_str(), spacingThatFits(h, dexels + faces, double(budget.bytes) - base),
                      moreMemoryAdvice(budget).c_str());
        throw Error(text);
    }
    if (fromStl) {
        // An open mesh casts a different solid into each family (a line that meets one face of
        // it keeps no material), which no surface can be rebuilt from.
        MeshCastStats cast;
        TriDexelStock stock = stockFromMesh(*fromStl, lattice, o.families, &cast);
        if (cast.unpairedDexels > 0)
            throw Error("stock '" + o.stockFile + "' is not closed: " + std::to_string(cast.unpairedDexels) +
                        " dexel lines meet an odd number of its faces; a stock must be a closed solid (repair the "
                        "mesh, or give --stock box:...)");
        return {std::move(stock), box, false, false};
    }
    if (fromVdb) return {stockFromLevelSet(*fromVdb, lattice, o.families), box, false, false};
    if (o.stockFrustum) return {stockFromFrustum(*o.stockFrustum, lattice, o.families), box, false, false};
    return {TriDexelStock::fromBox(box, h, o.families), box, true, aroundDesign};
}

Simulation runStages(const SimulateOptions& o);
SimulateReport simulateInArena(const SimulateOptions& o);

}  // namespace

Simulation runSimulation(const SimulateOptions& o) {
    // Every stage's parallel work runs in one arena of the requested size.
    tbb::task_arena arena(arenaThreads(o.threads));
    return arena.execute([&] { return runStages(o); });
}

namespace {

/// Limits a reader's moves to what the memory budget holds, and says so in the reader's message
/// when the budget is what sets the limit. Options: GcodeOptions or AptOptions.
template <class Options>
Options readerOptions(double chordTolerance, const MemoryBudget& budget) {
    Options o;
    o.chordTolerance = chordTolerance;
    // The moves a program makes (its loops included) must fit in memory.
    const std::size_t readerLimit = o.maxMoves;
    o.maxMoves = movesThatFit(budget, readerLimit);
    if (o.maxMoves < readerLimit)
        o.maxMovesReason = "the moves of a longer program would not fit in the memory this job may use, " +
                           formatBytes(double(budget.bytes)) + " (" + budget.source + ")";
    return o;
}

}  // namespace

std::vector<NamedFile> jobInputFiles(const SimulateOptions& o) {
    std::vector<NamedFile> files;
    if (!o.program)
        for (const std::string& in : o.inputs) files.push_back({"INPUTS", in});
    files.push_back({"--stock", o.stockFile});
    files.push_back({"--tool-table", o.toolTable});
    files.push_back({"--design", o.designPath});
    const std::vector<std::string> builtin = builtinMachineNames();
    if (std::find(builtin.begin(), builtin.end(), o.machine) == builtin.end()) files.push_back({"--machine", o.machine});
    return files;
}

GcodeOptions jobGcodeOptions(double chordTolerance, const MemoryBudget& budget) {
    return readerOptions<GcodeOptions>(chordTolerance, budget);
}

AptOptions jobAptOptions(double chordTolerance, const MemoryBudget& budget) {
    return readerOptions<AptOptions>(chordTolerance, budget);
}

namespace {

/// Before the rebuild: the level set and mesh of the cut part, from its crossings, must fit.
void checkSurfaceFits(const TriDexelStock& stock, const MemoryBudget& budget) {
    const double crossings = stockCrossings(stock);
    const double need = kSurfaceBytesPerCrossing * crossings;
    const double base = double(bytesInUse(budget));
    if (base + need <= double(budget.bytes)) return;
    const double h = stock.lattice().h;
    char text[512];
    std::snprintf(text, sizeof text,
                  "the cut part's surface crosses %.4g lattice edges at a spacing of %g mm: its level set and mesh "
                  "need about %s on top of the %s in use, more than the %s this job may use (%s); a spacing of "
                  "%g mm or more fits%s",
                  crossings, h, formatBytes(need).c_str(), formatBytes(base).c_str(),
                  formatBytes(double(budget.bytes)).c_str(), budget.source.c_str(),
                  spacingThatFits(h, base + need, double(budget.bytes)), moreMemoryAdvice(budget).c_str());
    throw Error(text);
}

/// The threads the process started since it had `before` (none if it has fewer now).
std::size_t threadsSince(std::size_t before) {
    const std::size_t now = processThreadCount();
    return now > before ? now - before : 0;
}

Simulation runStages(const SimulateOptions& o) {
    const auto tStart = Clock::now();
    const std::size_t threadsBefore = processThreadCount();
    Simulation sim;
    SimulateReport& report = sim.report;
    report.version = DEXELMILL_VERSION;
    report.inputs = o.inputs;
    report.families = o.families.str();
    if (o.inputs.empty() && !o.program) throw Error("nothing to simulate: give a project or at least one program");
    checkOutputs(o);

    // Parse.
    auto t = Clock::now();
    const MemoryBudget budget = memoryBudget(o.maxMemoryBytes);
    // A budget the process has spent before it starts would fail the first check of the readers,
    // and blame the program's length.
    if (const std::size_t held = bytesInUse(budget); held >= budget.bytes)
        throw Error("the memory this job may use, " + formatBytes(double(budget.bytes)) + " (" + budget.source +
                    "), is less than the " + formatBytes(double(held)) + " the process holds before it reads the "
                    "programs" + (budget.enforced ? "" : ": give a larger --max-memory"));
    GcodeOptions gcode = jobGcodeOptions(o.chordTolerance, budget);
    gcode.files = o.files;
    if (!o.machine.empty()) gcode.machine = loadMachine(o.machine, o.files);
    if (o.startPosition) gcode.startPosition = o.startPosition;
    const AptOptions apt = jobAptOptions(o.chordTolerance, budget);
    std::optional<Project> project;
    Program& program = sim.program;
    if (o.program) {
        program = *o.program;
    } else if (lowerExtension(o.inputs[0]) == ".camotics") {
        // A project, and optionally programs that replace its own (its tools, workpiece and
        // resolution still apply).
        project = readCamoticsProject(o.inputs[0], o.files);
        if (o.inputs.size() > 1) {
            std::string own;
            for (const ProjectFile& f : project->files) own += (own.empty() ? "" : ", ") + f.path;
            // Named, not braced in place: GCC 12 warns falsely of its string otherwise.
            SourceLocation projectFile;
            projectFile.file = project->file;
            project->diagnostics.push_back({Diagnostic::Severity::Note, projectFile,
                                            "the programs given after the project replace its own (" +
                                                (own.empty() ? std::string("none") : own) +
                                                "); its tools, workpiece and resolution still apply"});
            project->files.clear();
            for (auto in = o.inputs.begin() + 1; in != o.inputs.end(); ++in) project->files.push_back({*in, {}});
        }
        for (const ProjectFile& f : project->files)
            if (lowerExtension(f.path) == ".camotics")
                throw Error("'" + f.path + "': only the first input may be a project");
        program = runProject(*project, gcode);
    } else {
        for (const std::string& in : o.inputs) {
            if (lowerExtension(in) == ".camotics")
                throw Error("'" + in + "': a project must be the first input");
            program.append(readProgram(in, gcode, apt));
        }
    }
    sim.tools = detail::resolveTools(o, program);
    const ToolTable& tools = sim.tools;
    report.timingS.parse = seconds(t);

    report.moves = program.path.moves.size();
    report.rapids = std::size_t(std::count_if(program.path.moves.begin(), program.path.moves.end(),
                                              [](const Move& m) { return m.rapid; }));
    report.toolChanges = program.path.toolChanges.size();
    report.movesNotSimulated = program.movesNotSimulated;
    std::vector<ReportWarning> jobWarnings;
    if (!budget.note.empty()) {
        ReportWarning w;
        w.message = budget.note;
        jobWarnings.push_back(w);
    }
    if (std::string cut = threadsCutNote(o.threads); !cut.empty()) {
        ReportWarning w;
        w.message = std::move(cut);
        jobWarnings.push_back(w);
    }
    if (program.path.moves.empty()) {
        ReportWarning w;
        if (!o.inputs.empty()) w.where.file = o.inputs.back();
        w.message = "the program makes no moves: the part is the stock";
        jobWarnings.push_back(w);
    }
    // The design's mesh first: with no stock given, its box is the stock's.
    std::optional<Mesh> designMesh;
    MeshCheck designCheck;
    if (!o.designPath.empty()) {
        t = Clock::now();
        if (o.progress) o.progress("design", 0, 1);
        designMesh = readDesign(o.designPath, o.designTransform);
        report.timingS.design = seconds(t);
    }
    LoadedStock loaded = loadStock(o, budget, program, tools, project ? &*project : nullptr,
                                   designMesh ? &*designMesh : nullptr, report, jobWarnings);
    checkTurningMoves(program.path, tools, loaded.box, jobWarnings);
    if (designMesh) {
        // A stock made from the design's box holds it; a stock the user gave may not.
        if (!loaded.aroundDesign)
            noteDesignBeyondStock(designMesh->bounds(), loaded.box, o.designPath, jobWarnings);
        designCheck = checkMesh(*designMesh);
        report.designClosed = designCheck.closedManifold();
    }
    sim.stock.emplace(std::move(loaded.stock));
    TriDexelStock& stock = *sim.stock;
    report.stockBox = loaded.box;
    report.resolutionMm = stock.lattice().h;
    report.lattice = stock.lattice().n;
    noteArcChords(program, report.resolutionMm, o.chordTolerance, jobWarnings);
    for (int a = 0; a < 3; ++a) {
        const Axis ax = axisFromIndex(a);
        if (stock.has(ax)) report.dexels[a] = std::size_t(stock.family(ax).nb()) * std::size_t(stock.family(ax).nc());
    }
    // The stock's volume as the first kept family measures it (z preferred).
    const Axis measure = stock.measuringFamily();
    report.stockVolumeMm3 = stock.volume(measure);

    // The design, on the stock's lattice.
    std::optional<DesignPart> design;
    // The design's distance outlives its dexels: the mesh is measured against it at the end.
    std::unique_ptr<MeshDistance> designDistance;
    if (designMesh) {
        t = Clock::now();
        design.emplace(loadDesign(std::move(*designMesh), o.designPath, stock.lattice(), o.families, measuresSurface(o)));
        designMesh.reset();
        if (design->cast.unpairedDexels > 0) {
            ReportWarning w;
            w.where.file = o.designPath;
            w.message = "the design is not closed: " + std::to_string(design->cast.unpairedDexels) +
                        " dexels met an odd number of its faces; its solid there is a guess";
            jobWarnings.push_back(w);
        } else if (!report.designClosed) {
            ReportWarning w;
            w.where.file = o.designPath;
            w.message = "the design's mesh is not closed (" + designCheck.openness() +
                        "); every dexel met its faces in pairs, but distances near the gaps may take the wrong sign";
            jobWarnings.push_back(w);
        }
        report.designFile = o.designPath;
        report.gougeToleranceMm = o.gougeTolerance;
        report.timingS.design += seconds(t);
    }

    // Cut.
    t = Clock::now();
    CutOptions cutOptions;
    cutOptions.threads = arenaThreads(o.threads);
    cutOptions.turnTolerance = o.turnTolerance;
    if (design) {
        cutOptions.design = &design->dexels;
        cutOptions.designDepth = o.gougeTolerance;
        cutOptions.designBounds = design->bounds;
    }
    if (o.progress) cutOptions.progress = [&](std::size_t done, std::size_t total) { o.progress("cutting", done, total); };
    const CutResult cut = cutStock(stock, program.path, tools, cutOptions);
    report.timingS.cut = seconds(t);
    if (design) {
        // The gouges' depths (and the distance index, built when first needed) are the design's.
        t = Clock::now();
        for (const Gouge& g : findGouges(*design, stock.lattice(), cut, o.gougeTolerance)) {
            const Move& mv = program.path.moves[g.move];
            const SourceLocation at = program.path.where(mv.source);
            report.gouges.push_back(
                {ToolPath::moveNumber(g.move), at, mv.tool, mv.rapid, g.depth, g.volume, g.point});
        }
        std::stable_sort(report.gouges.begin(), report.gouges.end(),
                         [](const ReportGouge& a, const ReportGouge& b) { return a.depthMm > b.depthMm; });
        report.timingS.design += seconds(t);
    }
    if (design) {
        t = Clock::now();
        const Excess excess = findExcess(*design, stock, o.excessTolerance);
        report.excessToleranceMm = o.excessTolerance;
        report.excessVolumeMm3 = excess.volume;
        report.excessThicknessMm = excess.thickness;
        report.excessPoint = excess.point;
        for (const ExcessRegion& r : excess.regions)
            report.excessRegions.push_back({r.box, r.volume, r.thickness, r.point});
        if (measuresSurface(o)) designDistance = design->takeDistance();
        design.reset();
        report.timingS.design += seconds(t);
    }
    for (const CutCollision& c : cut.collisions) {
        const SourceLocation at = program.path.where(c.source);
        const char* kind = c.kind == CollisionKind::Rapid   ? "rapid"
                           : c.kind == CollisionKind::Shank ? "shank"
                                                            : "holder";
        report.collisions.push_back({ToolPath::moveNumber(c.move), at, kind, c.volume});
    }
    for (int a = 0; a < 3; ++a)
        if (stock.has(axisFromIndex(a))) report.familyVolumesMm3[a] = stock.volume(axisFromIndex(a));
    report.finalVolumeMm3 = stock.volume(measure);
    report.removedVolumeMm3 = report.stockVolumeMm3 - report.finalVolumeMm3;
    report.fineFeatures = finerThanLattice(stock);
    noteFineFeatures(report.fineFeatures, stock.lattice().h, report.finalVolumeMm3, o.mesher,
                     jobWarnings);
    // The job's own warnings first (a thread count cut, the stock it chose, an open design): a long
    // program's diagnostics would push them past what the summary prints.
    for (ReportWarning& n : jobWarnings) report.warnings.push_back(std::move(n));
    for (const Diagnostic& d : program.diagnostics)
        report.warnings.push_back({d.where, d.message, d.severity});
    report.stockMemoryBytes = stock.memoryBytes();
    checkSurfaceFits(stock, budget);

    // Rebuild and mesh.
    t = Clock::now();
    if (o.progress) o.progress("rebuild", 0, 1);
    RebuildOptions rebuild;
    rebuild.source = o.inputs.empty() ? std::string("program in memory") : o.inputs.front();
    rebuild.families = o.families;
    sim.levelSet = rebuildLevelSet(stock, rebuild);
    report.timingS.rebuild = seconds(t);
    t = Clock::now();
    if (o.progress) o.progress("mesh", 0, 1);
    MeshCheck check;
    if (o.mesher == Mesher::Dexel) {
        ContourOptions contour;
        contour.adaptivity = o.adaptivity;
        ContourStats stats;
        sim.mesh = contourStock(sim.levelSet, stock, contour, &stats);
        check = stats.check;
        report.mesher = "dexel";
        report.exactCrossings = stats.exactCrossings;
        report.interpolatedCrossings = stats.crossings - stats.exactCrossings;
        report.edgeVertices = stats.edgeVertices;
        report.cornerVertices = stats.cornerVertices;
        report.plainCells = stats.plainCells;
        report.splitEdges = stats.splitEdges;
        report.splitEdgesDropped = stats.splitEdgesDropped;
        report.splitCells = stats.splitCells;
        report.faceVertices = stats.faceVertices;
        report.patchPairsLeftCrossing = stats.patchPairsLeftCrossing;
        report.meshRuns = stats.splitRuns;
        if (stats.splitEdgesDropped > 0) {
            char text[300];
            std::snprintf(text, sizeof text,
                          "the mesh leaves out the thin walls and slots on %zu of the %zu lattice edges that cross "
                          "them more than once, where their triangles would fold",
                          stats.splitEdgesDropped, stats.splitEdgesDropped + stats.splitEdges);
            ReportWarning w;
            w.message = text;
            report.warnings.push_back(w);
        }
    } else {
        MeshOptions meshOptions;
        meshOptions.adaptivity = o.adaptivity;
        sim.mesh = meshLevelSet(sim.levelSet, meshOptions);
        check = checkMesh(sim.mesh);
        report.mesher = "vdb";
        if (o.adaptivity > 0.0) {
            ReportWarning w;
            w.message = "--adaptivity with --mesher vdb is OpenVDB's own: it merges across the level set with no bound "
                        "on how far the surface moves (walls more than a spacing in, at 1); the dexel mesher's keeps "
                        "within 0.05 spacings";
            report.warnings.push_back(w);
        }
    }
    report.timingS.mesh = seconds(t);

    // Refine against the exact part: the sweeps the cutting loop subtracted, moves whose axis
    // turns within the same tolerance.
    if (o.refineRounds > 0 && !loaded.isBox) {
        ReportWarning w;
        w.where.file = o.stockFile;
        w.message = "--refine needs a box stock: the mesh of a round stock or a stock from a file is not refined";
        report.warnings.push_back(w);
    } else if (o.refineRounds > 0) {
        t = Clock::now();
        if (o.progress) o.progress("refine", 0, 1);
        RefineOptions refine;
        refine.rounds = o.refineRounds;
        refine.tolerance = o.refineTolerance * stock.lattice().h;
        refine.turnTolerance = o.turnTolerance;
        refine.progress = o.progress;
        refine.window = 0.5 * stock.lattice().h;
        refine.memoryBytes = std::max(0.0, double(budget.bytes) - double(bytesInUse(budget)));
        RefineStats stats;
        refineMesh(sim.mesh, report.stockBox, program.path, tools, refine, &stats);
        check = stats.check;
        if (stats.roundNeeded > 0.0) {
            char text[400];
            std::snprintf(text, sizeof text,
                          "--refine %d: stopped after %d round(s): the next would need about %s on top of the %s "
                          "in use, more than the %s this job may use (%s)",
                          o.refineRounds, stats.rounds, formatBytes(stats.roundNeeded).c_str(),
                          formatBytes(double(bytesInUse(budget))).c_str(), formatBytes(double(budget.bytes)).c_str(),
                          budget.source.c_str());
            ReportWarning w;
            w.message = text;
            report.warnings.push_back(w);
        }
        report.refineRounds = stats.rounds;
        report.refineQueries = stats.queries;
        report.refineSplit = stats.split;
        report.refineSnapped = stats.snapped;
        report.refineSnapPartial = stats.snapPartial;
        report.refineRefused = stats.refused;
        report.refineCrossed = stats.crossed;
        report.refineNoCrossing = stats.noCrossing;
        report.refineLaterAxis = stats.laterAxis;
        report.refineCollapsed = stats.collapsed;
        report.timingS.refine = seconds(t);
    }
    const Mesh& mesh = sim.mesh;
    // The surface against the design, when something shows it.
    if (designDistance && measuresSurface(o)) {
        t = Clock::now();
        if (o.progress) o.progress("deviation", 0, 1);
        Deviation deviation = measureDeviation(mesh, *designDistance, {o.gougeTolerance, o.excessTolerance});
        sim.deviation = std::move(deviation.distance);
        report.surfaceDeviation = std::move(deviation);
        report.timingS.design += seconds(t);
    }
    report.meshVertices = mesh.vertices.size();
    report.meshTriangles = mesh.triangles.size();
    report.meshClosed = check.closedManifold();
    report.meshFoldedTriangles = check.foldedTriangles;
    report.meshDegenerateTriangles = check.degenerateTriangles;
    report.meshVolumeMm3 = check.signedVolume;
    report.timingS.total = seconds(tStart);
    report.peakMemoryMb = peakMemoryMb();
    report.heapOnHugePages = heapOnHugePages();
    report.threadsStarted = threadsSince(threadsBefore);
    return sim;
}

}  // namespace

SimulateReport simulate(const SimulateOptions& o) {
    tbb::task_arena arena(arenaThreads(o.threads));
    return arena.execute([&] { return simulateInArena(o); });
}

namespace {

SimulateReport simulateInArena(const SimulateOptions& o) {
    const auto tStart = Clock::now();
    const std::size_t threadsBefore = processThreadCount();
    Simulation sim = runStages(o);
    SimulateReport& report = sim.report;
    const Mesh& mesh = sim.mesh;

    // Write: every file is staged, and renamed only once all are written.
    auto t = Clock::now();
    if (o.progress) o.progress("write", 0, 1);
    OutputBatch outputs;
    if (!o.meshPath.empty()) {
        const std::string e = meshFormat(o.meshPath);
        if (e == ".obj") writeObj(o.meshPath, mesh, &outputs);
        else if (e == ".stl") writeStl(o.meshPath, mesh, &outputs);
        else writePly(o.meshPath, mesh, {}, &outputs);
    }
    if (!o.vdbPath.empty()) writeVdb(o.vdbPath, sim.levelSet, &outputs);
    if (report.surfaceDeviation) {
        writeDeviationFiles(mesh, *report.surfaceDeviation, std::move(sim.deviation), o.pngPath, o.deviationPlyPath,
                            outputs);
    } else if (!o.pngPath.empty()) {
        writePicture(o.pngPath, mesh, {}, &outputs);
    }
    if (!o.gougeCsvPath.empty()) {
        const std::string text = gougeCsv(report);
        writeStreamAtomically(o.gougeCsvPath, [&](std::ostream& out) { out << text; }, &outputs);
    }
    report.timingS.write = seconds(t);
    report.timingS.total = seconds(tStart);
    report.peakMemoryMb = peakMemoryMb();
    report.heapOnHugePages = heapOnHugePages();
    report.threadsStarted = threadsSince(threadsBefore);
    if (!o.reportPath.empty()) {
        const std::string text = reportJson(report);
        writeStreamAtomically(o.reportPath, [&](std::ostream& out) { out << text; }, &outputs);
    }
    outputs.commit();
    return report;
}

}  // namespace

}  // namespace dexelmill
