// `dexelmill info FILE`: what a program, project or VDB file holds.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <set>

#include "commands.h"
#include "dexelmill/error.h"
#include "dexelmill/io/vdb_io.h"
#include "dexelmill/job/memory.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/path/camotics.h"
#include "dexelmill/surface/levelset.h"
#include "wording.h"

namespace dexelmill::cli {

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
    if (s.size() < suffix.size()) return false;
    for (std::size_t i = 0; i < suffix.size(); ++i)
        if (std::tolower(static_cast<unsigned char>(s[s.size() - suffix.size() + i])) != suffix[i]) return false;
    return true;
}

void printBox(const char* label, const Box& b) {
    if (b.isEmpty()) {
        std::printf("%-14s none\n", label);
        return;
    }
    std::printf("%-14s x %.4g .. %.4g, y %.4g .. %.4g, z %.4g .. %.4g mm\n", label, b.lo.x, b.hi.x, b.lo.y, b.hi.y,
                b.lo.z, b.hi.z);
}

void printProgram(const Program& p) {
    std::size_t rapids = 0;
    double feedLength = 0, rapidLength = 0;
    Box cutting;
    std::size_t vertical = 0, tilted = 0, turning = 0;
    for (const Move& m : p.path.moves) {
        const double len = tipLength(m);
        if (m.rapid) {
            ++rapids;
            rapidLength += len;
        } else {
            feedLength += len;
            cutting.expand(tipBounds(m));
        }
        if (m.turns()) ++turning;
        else if (std::abs(m.axis.z - 1.0) <= 1e-12) ++vertical;
        else ++tilted;
    }
    std::printf("%-14s %zu (%zu rapid), feed %.6g mm, rapid %.6g mm\n", "moves", p.path.moves.size(), rapids,
                feedLength, rapidLength);
    if (p.movesNotSimulated > 0)
        std::printf("%-14s %zu more, from or to a position the program does not state (the warnings say where)\n",
                    "not simulated", p.movesNotSimulated);
    std::printf("%-14s %zu\n", "tool changes", p.path.toolChanges.size());
    std::printf("%-14s %zu 3-axis (+z), %zu 3+2 (fixed, tilted), %zu simultaneous multi-axis (the axis or a "
                "rotary table turns)\n",
                "moves by axis", vertical, tilted, turning);
    for (int a = 0; a < 3; ++a) {
        const Interval& r = p.rotaryRanges[std::size_t(a)];
        if (!r.isEmpty()) std::printf("%-14s %c %.6g .. %.6g degrees\n", "rotary range", char('A' + a), r.lo, r.hi);
    }
    printBox("extent", p.path.bounds());
    printBox("cutting", cutting);
    // Every tool number the program defines or moves with (0 for moves before any tool change),
    // and for those it moves with undefined, what simulate does (resolveTools): with one tool
    // defined it cuts with that one, otherwise it needs a --tool.
    std::set<int> numbers;
    for (const auto& [n, t] : p.tools) numbers.insert(n);
    for (const Move& m : p.path.moves) numbers.insert(m.tool);
    for (int n : numbers) {
        const auto defined = p.tools.find(n);
        const std::string name = n == 0 ? std::string("T0 (no tool selected)") : "T" + std::to_string(n);
        const std::string option = n == 0 ? std::string("--tool SPEC") : "--tool " + std::to_string(n) + "=SPEC";
        if (defined != p.tools.end())
            std::printf("%-14s %s: %s\n", "tool", name.c_str(), defined->second.description().c_str());
        else if (const std::optional<int> only = standInTool(p.tools))
            std::printf("%-14s %s: not defined; simulate cuts with the only tool defined, T%d (%s), unless given %s\n",
                        "tool", name.c_str(), *only, p.tools.at(*only).description().c_str(), option.c_str());
        else
            std::printf("%-14s %s: no cutter defined; give one with %s\n", "tool", name.c_str(), option.c_str());
    }
    const auto isNote = [](const Diagnostic& d) { return d.severity == Diagnostic::Severity::Note; };
    const std::size_t notes = std::size_t(std::count_if(p.diagnostics.begin(), p.diagnostics.end(), isNote));
    std::printf("%-14s %zu\n", "warnings", p.diagnostics.size() - notes);
    if (notes > 0) std::printf("%-14s %zu\n", "notes", notes);
    constexpr std::size_t kShown = 10;
    for (std::size_t i = 0; i < p.diagnostics.size() && i < kShown; ++i)
        std::printf("  %s: %s: %s\n", p.diagnostics[i].where.str().c_str(), isNote(p.diagnostics[i]) ? "note" : "warning",
                    p.diagnostics[i].message.c_str());
    if (p.diagnostics.size() > kShown) {
        const std::size_t hiddenNotes = std::size_t(std::count_if(p.diagnostics.begin() + kShown, p.diagnostics.end(), isNote));
        const std::size_t hidden = p.diagnostics.size() - kShown;
        std::printf("  ... and %s ('simulate' prints them all)\n", moreDiagnostics(hidden - hiddenNotes, hiddenNotes).c_str());
    }
}

}  // namespace

CLI::App* addInfo(CLI::App& app, InfoArgs& a) {
    CLI::App* c = app.add_subcommand("info", "What a program, project or VDB file holds: moves, tools, extents.");
    c->add_option("FILE", a.file, "A G-code or APT program, a .camotics project or a .vdb file")->required();
    c->add_option("--machine", a.machine,
                  "NAME or FILE.json: the machine whose rotary axes a G-code program turns (as for simulate)");
    c->add_option("--start", a.start, kStartHelp);
    return c;
}

int runInfo(const InfoArgs& args) {
    const std::string& file = args.file;
    // Checked before anything is read, whatever the file: a malformed option is an error.
    const std::optional<Vec3> start = parseStart(args.start);
    // Each kind of file is read whole (with the machine it needs) before its first line is
    // printed: an error is not left after part of the summary.
    if (endsWith(file, ".vdb")) {
        // A level set has no moves for a machine to turn or a start to begin from.
        for (const auto& [given, option] : {std::pair{!args.machine.empty(), "--machine"}, std::pair{bool(start), "--start"}})
            if (given) throw UsageError(std::string("info: ") + option + " applies to a program; '" + file + "' is a level set");
        const LevelSet ls = readVdb(file);
        std::printf("%-14s %s\n", "file", file.c_str());
        std::printf("%-14s OpenVDB level set, voxel %.6g mm, half-width %.3g voxels\n", "kind", ls.voxelSize(),
                    ls.halfWidth());
        std::printf("%-14s %zu active voxels in %zu leaves, %.1f MiB\n", "grid", ls.activeVoxelCount(), ls.leafCount(),
                    double(ls.memoryBytes()) / (1 << 20));
        printBox("active", ls.activeBounds());
        if (!ls.source().empty()) std::printf("%-14s %s\n", "source", printable(ls.source()).c_str());
        return 0;
    }
    const MemoryBudget budget = memoryBudget();
    GcodeOptions gcode = jobGcodeOptions(SimulateOptions().chordTolerance, budget);
    if (!args.machine.empty()) gcode.machine = loadMachine(args.machine);
    gcode.startPosition = start;
    if (endsWith(file, ".camotics")) {
        const Project project = readCamoticsProject(file);
        const Program program = runProject(project, gcode);
        // As the job takes it: fixed bounds where the project gives them, else the automatic box.
        const bool automatic = project.workpiece.automatic || project.workpiece.bounds.isEmpty();
        const Box workpiece = automatic ? automaticWorkpieceBounds(program, project.workpiece.marginPercent)
                                        : project.workpiece.bounds;
        std::printf("%-14s %s\n", "file", file.c_str());
        std::printf("%-14s CAMotics project, %s units\n", "kind", project.metric ? "metric" : "imperial");
        for (const ProjectFile& f : project.files) std::printf("%-14s %s\n", "program", f.path.c_str());
        if (automatic) {
            std::printf("%-14s %sautomatic, margin %.3g %%\n", "workpiece",
                        project.workpiece.automatic ? "" : "no bounds given: ", project.workpiece.marginPercent);
            printBox("stock", workpiece);
        } else {
            printBox("workpiece", workpiece);
        }
        if (project.resolutionMode != ResolutionMode::Manual) {
            static const char* const kModes[] = {"manual", "low", "medium", "high", "very high"};
            const char* mode = kModes[int(project.resolutionMode)];
            if (workpiece.isEmpty())
                std::printf("%-14s %s, from the workpiece\n", "resolution", mode);
            else
                std::printf("%-14s %.6g mm (%s, from the workpiece)\n", "resolution",
                            projectResolution(project.resolutionMode, workpiece), mode);
        } else if (project.resolution > 0) {
            std::printf("%-14s %.6g mm (manual)\n", "resolution", project.resolution);
        }
        printProgram(program);
        return 0;
    }
    const Program program = readProgram(file, gcode, jobAptOptions(SimulateOptions().chordTolerance, budget));
    std::printf("%-14s %s\n", "file", file.c_str());
    printProgram(program);
    return 0;
}

}  // namespace dexelmill::cli
