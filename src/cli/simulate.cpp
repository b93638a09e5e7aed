// `dexelmill simulate`: options to SimulateOptions, run the job, print warnings and a summary.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include <sys/stat.h>
#include <unistd.h>

#include "commands.h"
#include "dexelmill/decimal.h"
#include "dexelmill/error.h"
#include "dexelmill/job/memory.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/tool/spec.h"
#include "progress.h"
#include "wording.h"

namespace dexelmill::cli {

namespace {

/// Most warnings and collisions printed one by one; the rest are counted (all are in --report).
constexpr std::size_t kPrintedDiagnostics = 20;

/// The comma-separated numbers of an option's value; `option` names it in the message. Every
/// field holds a number: "1,2," is refused, not read as two.
std::vector<double> parseNumbers(const std::string& text, const std::string& option) {
    std::vector<double> v;
    for (const std::string& item : splitAtCommas(text)) {
        if (item.empty()) throw UsageError(option + ": '" + text + "' has an empty value");
        const std::optional<double> x = parseDecimal(item);
        if (!x) throw UsageError(option + ": '" + item + "' is not a number");
        v.push_back(*x);
    }
    return v;
}

/// Refuses a coordinate or a size beyond where a program may reach, kMaxCoordinateMm: far beyond
/// it a stock's sizes are lost to rounding (a cylinder 10 mm high at z = 1e300 has no height).
/// `option` and `name` (possibly empty) say which value it is.
void requireWithinReach(const std::string& option, const std::string& name, double x) {
    if (std::abs(x) <= kMaxCoordinateMm) return;
    throw UsageError(option + ": " + (name.empty() ? "" : name + " = ") + decimalsApart(x, kMaxCoordinateMm).first +
                     " mm is beyond the 1e9 mm a program may reach");
}

Box parseBox(const std::string& text) {
    const std::vector<double> v = parseNumbers(text, "--stock box");
    if (v.size() != 6) throw UsageError("--stock box: expected XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX (6 numbers, mm)");
    const char* const names[] = {"XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"};
    for (std::size_t i = 0; i < v.size(); ++i) requireWithinReach("--stock box", names[i], v[i]);
    const Box b{Vec3(v[0], v[1], v[2]), Vec3(v[3], v[4], v[5])};
    if (!(b.lo.x < b.hi.x && b.lo.y < b.hi.y && b.lo.z < b.hi.z))
        throw UsageError("--stock box: each minimum must be below its maximum");
    return b;
}

/// A round stock along a coordinate axis: `cylinder:AXIS,X,Y,Z,R,H` or
/// `cone:AXIS,X,Y,Z,R0,R1,H` (`kind` says which; `text` follows the colon). AXIS is x, y or z,
/// with an optional sign (-z points down); X,Y,Z the base face's centre; R0 the radius there, R1
/// at the face H further along the axis.
Frustum parseRoundStock(const std::string& kind, const std::string& text) {
    const bool cone = kind == "cone";
    const std::string form = cone ? "cone:AXIS,X,Y,Z,R0,R1,H" : "cylinder:AXIS,X,Y,Z,R,H";
    const std::size_t comma = text.find(',');
    std::string letter = text.substr(0, comma);
    double sign = 1.0;
    if (!letter.empty() && (letter[0] == '-' || letter[0] == '+')) {
        sign = letter[0] == '-' ? -1.0 : 1.0;
        letter = letter.substr(1);
    }
    Vec3 axis(0.0);
    if (letter == "x" || letter == "X") axis.x = sign;
    else if (letter == "y" || letter == "Y") axis.y = sign;
    else if (letter == "z" || letter == "Z") axis.z = sign;
    else throw UsageError("--stock " + form + ": the axis '" + letter + "' is not x, y or z (optionally -x, -y, -z)");
    const std::vector<double> v =
        comma == std::string::npos ? std::vector<double>{} : parseNumbers(text.substr(comma + 1), "--stock " + kind);
    const std::size_t want = cone ? 6 : 5;
    if (v.size() != want)
        throw UsageError("--stock " + form + ": expected the axis and " + std::to_string(want) +
                         " numbers (mm): the base face's centre, " + (cone ? "its radius, the far face's radius" : "the radius") +
                         " and the height");
    const char* const coneNames[] = {"X", "Y", "Z", "R0", "R1", "H"};
    const char* const cylinderNames[] = {"X", "Y", "Z", "R", "H"};
    for (std::size_t i = 0; i < want; ++i) requireWithinReach("--stock " + form, (cone ? coneNames : cylinderNames)[i], v[i]);
    try {
        return Frustum::make(Vec3(v[0], v[1], v[2]), axis, v[want - 1], v[3], cone ? v[4] : v[3]);
    } catch (const Error& e) {
        throw UsageError("--stock " + form + ": " + e.what());
    }
}

}  // namespace

const char* const kStartHelp =
    "X,Y,Z: where the machine stands when a G-code program starts (mm). Unset, moves only\n"
    "set the position until the program has given X, Y and Z (for example a 4-axis\n"
    "program that never names Y needs --start)";

std::vector<std::string> splitAtCommas(const std::string& text) {
    std::vector<std::string> fields;
    if (text.empty()) return fields;
    std::size_t start = 0;
    for (std::size_t comma = text.find(','); comma != std::string::npos; comma = text.find(',', start)) {
        fields.push_back(text.substr(start, comma - start));
        start = comma + 1;
    }
    fields.push_back(text.substr(start));
    return fields;
}

std::optional<Vec3> parseStart(const std::string& text) {
    if (text.empty()) return std::nullopt;
    const std::vector<double> v = parseNumbers(text, "--start");
    if (v.size() != 3) throw UsageError("--start takes X,Y,Z (mm)");
    // A program's own positions stop there too (a move from 1e300 mm cut 85 of its 612.5 mm^3).
    for (const double x : v) requireWithinReach("--start", "", x);
    return Vec3(v[0], v[1], v[2]);
}

Affine parseTransform(const std::string& text) {
    const std::vector<double> v = parseNumbers(text, "--design-transform");
    Affine a;
    if (v.size() == 3) {
        a.t = Vec3(v[0], v[1], v[2]);
    } else if (v.size() == 12) {
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) a.m[std::size_t(r)][std::size_t(c)] = v[std::size_t(4 * r + c)];
            a.t[r] = v[std::size_t(4 * r + 3)];
        }
    } else {
        throw UsageError("--design-transform: expected TX,TY,TZ or the 3 rows of a 3 x 4 matrix, M11,M12,M13,TX,"
                         "M21,...,TZ (12 numbers)");
    }
    return a;
}

SimulateOptions toOptions(const SimulateArgs& a) {
    SimulateOptions o;
    o.inputs = a.inputs;
    if (!a.stock.empty()) {
        if (a.stock.rfind("box:", 0) == 0) o.stockBox = parseBox(a.stock.substr(4));
        else if (a.stock.rfind("cylinder:", 0) == 0) o.stockFrustum = parseRoundStock("cylinder", a.stock.substr(9));
        else if (a.stock.rfind("cone:", 0) == 0) o.stockFrustum = parseRoundStock("cone", a.stock.substr(5));
        else o.stockFile = a.stock;
    }
    for (const std::string& t : a.tools) {
        // N=SPEC gives tool N; a bare SPEC serves every tool number nobody defines.
        const std::size_t eq = t.find('=');
        const std::size_t colon = t.find(':');
        try {
            if (eq != std::string::npos && (colon == std::string::npos || eq < colon)) {
                const std::string num = t.substr(0, eq);
                std::size_t used = 0;
                int n = -1;
                try {
                    n = std::stoi(num, &used);
                } catch (const std::exception&) {
                    used = 0;
                }
                if (used == 0 || used != num.size() || n < 0)
                    throw UsageError("--tool " + t + ": '" + num + "' is not a tool number");
                if (o.tools.count(n)) throw UsageError("--tool: tool " + num + " is given twice");
                o.tools.emplace(n, parseToolSpec(t.substr(eq + 1)));
            } else {
                if (o.defaultTool) throw UsageError("--tool: more than one tool without a number (use N=SPEC)");
                o.defaultTool = parseToolSpec(t);
            }
        } catch (const Error& e) {
            throw UsageError(std::string("--tool: ") + e.what());
        }
    }
    if (a.resolution < 0) throw UsageError("--resolution must be positive (mm)");
    o.resolution = a.resolution;
    try {
        o.families = FamilySet::parse(a.families);
    } catch (const Error& e) {
        throw UsageError(std::string("--families: ") + e.what());
    }
    o.chordTolerance = a.chordTolerance;
    const bool tooFine = a.turnTolerance < kMinTurnTolerance;
    if (tooFine || a.turnTolerance > kMaxTurnTolerance) {
        char text[300];
        std::snprintf(text, sizeof text, "--turn-tolerance: %g mm %s; give %g mm or %s", a.turnTolerance,
                      tooFine ? "is finer than the stock keeps (its dexel ends are floats, 8e-6 mm apart at 100 mm)"
                              : "would let a turning move be swept with one axis that far off",
                      tooFine ? kMinTurnTolerance : kMaxTurnTolerance, tooFine ? "more" : "less");
        throw UsageError(text);
    }
    o.turnTolerance = a.turnTolerance;
    o.toolTable = a.toolTable;
    if (a.toolTableUnits == "inch") o.toolTableUnit = 25.4;
    else if (a.toolTableUnits != "mm") throw UsageError("--tool-table-units must be mm or inch, got '" + a.toolTableUnits + "'");
    if (a.given.count("--tool-table-units") && a.toolTable.empty())
        throw UsageError("--tool-table-units needs --tool-table FILE.tbl");
    o.machine = a.machine;
    o.startPosition = parseStart(a.start);
    if (!(a.adaptivity >= 0.0 && a.adaptivity <= 1.0)) throw UsageError("--adaptivity must lie in [0, 1]");
    o.adaptivity = a.adaptivity;
    o.refineRounds = a.refineRounds;
    o.refineTolerance = a.refineTolerance;
    if (a.mesher == "dexel") o.mesher = Mesher::Dexel;
    else if (a.mesher == "vdb") o.mesher = Mesher::Vdb;
    else throw UsageError("--mesher must be dexel or vdb, got '" + a.mesher + "'");
    if (a.sharpEdges && o.mesher == Mesher::Vdb)
        throw UsageError("--sharp-edges: volumeToMesh rounds sharp edges; the dexel mesher (the default) keeps them");
    if (a.gougeCsv.size() && a.design.empty()) throw UsageError("--gouge-csv needs --design PART.stl");
    // Options that only serve another option are refused without it, not dropped.
    if (a.design.empty())
        for (const char* name : {"--gouge-tolerance", "--excess-tolerance"})
            if (a.given.count(name)) throw UsageError(std::string(name) + " needs --design PART.stl");
    if (a.given.count("--refine-tolerance") && a.refineRounds == 0)
        throw UsageError("--refine-tolerance needs --refine ROUNDS (1 or more)");
    for (const auto& [name, path] : {std::pair<const char*, const std::string&>{"--output", a.output},
                                     {"--vdb", a.vdb}, {"--png", a.png}, {"--report", a.report},
                                     {"--design", a.design}, {"--gouge-csv", a.gougeCsv},
                                     {"--deviation-ply", a.deviationPly}, {"--stock", a.stock},
                                     {"--machine", a.machine}, {"--tool-table", a.toolTable}})
        if (a.given.count(name) && path.empty()) throw UsageError(std::string(name) + ": the path is empty");
    o.designPath = a.design;
    if (!a.designTransform.empty()) {
        if (a.design.empty()) throw UsageError("--design-transform needs --design PART.stl");
        o.designTransform = parseTransform(a.designTransform);
    }
    o.gougeTolerance = a.gougeTolerance;
    o.excessTolerance = a.excessTolerance;
    o.gougeCsvPath = a.gougeCsv;
    if (a.deviationPly.size() && a.design.empty()) throw UsageError("--deviation-ply needs --design PART.stl");
    o.deviationPlyPath = a.deviationPly;
    o.meshPath = a.output;
    o.vdbPath = a.vdb;
    o.pngPath = a.png;
    o.reportPath = a.report;
    o.threads = a.threads;
    if (!a.maxMemory.empty()) {
        try {
            o.maxMemoryBytes = parseMemorySize(a.maxMemory);
        } catch (const Error& e) {
            throw UsageError(std::string("--max-memory: ") + e.what());
        }
    }
    return o;
}

namespace {

std::string where(const SourceLocation& l) { return l.file.empty() ? "dexelmill" : l.str(); }

}  // namespace

std::FILE* summaryStream(const std::vector<std::string>& outputs) {
    struct stat out {};
    // A terminal or /dev/null takes the summary after an output as well as stderr would.
    if (::fstat(STDOUT_FILENO, &out) != 0 || S_ISCHR(out.st_mode)) return stdout;
    for (const std::string& path : outputs) {
        struct stat st {};
        if (!path.empty() && ::stat(path.c_str(), &st) == 0 && st.st_dev == out.st_dev && st.st_ino == out.st_ino)
            return stderr;
    }
    return stdout;
}

void warnThreads(int requested) {
    const std::string cut = threadsCutNote(requested);
    if (!cut.empty()) std::fprintf(stderr, "dexelmill: warning: %s\n", cut.c_str());
}

void printDeviation(const Deviation& d) {
    const double pct = d.area > 0.0 ? 100.0 / d.area : 0.0;
    std::fprintf(stderr,
                 "dexelmill: surface against the design: %.1f %% within tolerance, %.1f %% gouged (deepest %s mm "
                 "at %.4f, %.4f, %.4f), %.1f %% excess (farthest %s mm at %.4f, %.4f, %.4f); RMS %s mm over "
                 "%s mm^2\n",
                 d.withinArea * pct, d.gougeArea * pct, lengthText(d.deepest < 0.0 ? -d.deepest : 0.0).c_str(),
                 d.deepestPoint.x, d.deepestPoint.y, d.deepestPoint.z, d.excessArea * pct, lengthText(d.farthest).c_str(),
                 d.farthestPoint.x, d.farthestPoint.y, d.farthestPoint.z, lengthText(d.rms).c_str(), areaText(d.area).c_str());
}

/// A number the option must have, checked as CLI11 reads it: the message names the value and what
/// is allowed (CLI11's own ranges print the largest double in full).
CLI::Validator numberCheck(bool zeroAllowed) {
    return CLI::Validator(
        [zeroAllowed](std::string& text) -> std::string {
            const std::optional<double> number = parseDecimal(text);
            if (!number) return "'" + text + "' is not a number";
            const double v = *number;
            if (v < 0 || (v == 0 && !zeroAllowed))
                return std::string("must be ") + (zeroAllowed ? "0 or more" : "positive") + ", got " + text;
            return {};
        },
        zeroAllowed ? "NONNEGATIVE" : "POSITIVE");
}

void addJobOptions(CLI::App& cmd, SimulateArgs& a, bool inputsRequired) {
    CLI::App* c = &cmd;
    CLI::Option* in =
        c->add_option("INPUTS", a.inputs, "PROJECT.camotics or PROGRAM... (.ngc, .nc, .gcode, .tap, .apt, .cl)");
    if (inputsRequired) in->required();
    c->parse_complete_callback([c, &a] {
        for (const CLI::Option* opt : c->get_options())
            if (opt->count() > 0 && !opt->get_lnames().empty()) a.given.insert("--" + opt->get_lnames().front());
    });
    c->add_option("--stock", a.stock,
                  "box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX | cylinder:AXIS,X,Y,Z,R,H |\n"
                  "cone:AXIS,X,Y,Z,R0,R1,H (bar stock, a turned blank: AXIS x, y or z, or -x...;\n"
                  "X,Y,Z the centre of the base face, R0 its radius, R1 the radius H along AXIS)\n"
                  "or FILE.stl / FILE.vdb (a casting, a forging, an earlier result); mm.\n"
                  "Default: the project's workpiece, else the program's extent.");
    c->add_option("--tool", a.tools,
                  "SPEC or N=SPEC, repeatable; N is the tool number used by T words.\n"
                  "SPEC: ball:d=6 | flat:d=10 | bull:d=10,r=2 | taper:d=2,angle=15 |\n"
                  "      chamfer:d=12,angle=45[,tip=T] | vbit:d=6,angle=30 | taperball:d=3,angle=5 |\n"
                  "      drill:d=6[,angle=118] | apt:D,R,E,F,ALPHA,BETA,H\n"
                  "      optional ,length=L (cutting length) ,total=T (stick-out from the holder)\n"
                  "      ,holder=D,holderlength=L (the holder above the stick-out, as one cylinder\n"
                  "      of its widest diameter; what it meets is a collision); mm, degrees.\n"
                  "      angle= is the HALF angle from the axis for taper, chamfer, vbit and taperball\n"
                  "      (a 60 degree V-bit is vbit:d=6,angle=30), the INCLUDED point angle for drill\n"
                  "      (118, not 59). d= is the TIP diameter for taper (it widens upward over the\n"
                  "      cutting length), the LARGEST for chamfer and vbit (the cone runs from tip=T,\n"
                  "      default 0, up to d), the ball's for taperball.\n"
                  "A bare SPEC serves every tool number nothing else defines.");
    c->add_option("--tool-table", a.toolTable,
                  "FILE.tbl: a LinuxCNC tool table (T P Z D ... ;comment lines) for the tool numbers the\n"
                  "program and --tool N=SPEC leave undefined. It gives no shape: each is cut as a flat\n"
                  "end mill of its diameter D, with a warning; --tool N=SPEC gives a shape");
    c->add_option("--tool-table-units", a.toolTableUnits,
                  "mm or inch: the units of the tool table (LinuxCNC's LINEAR_UNITS of the machine)")
        ->capture_default_str();
    c->add_option("--chord-tolerance", a.chordTolerance, "Largest arc-to-chord distance when arcs are linearised (mm)")
        ->check(numberCheck(false))
        ->capture_default_str();
    c->add_option("--turn-tolerance", a.turnTolerance,
                  "Tolerance of the sweep of a move whose tool axis turns (simultaneous 5-axis), in mm:\n"
                  "material deeper than this inside some pose of the tool is removed, and nothing the tool\n"
                  "never reaches is removed. From 1e-6 to 0.1; the time grows about as its inverse square root")
        ->check(numberCheck(false))
        ->capture_default_str();
    c->add_option("--machine", a.machine,
                  "NAME or FILE.json: the machine whose rotary axes A, B, C a G-code program turns.\n"
                  "Built-in: xyzac-trt and xyzbc-trt (LinuxCNC's sim configs: tilting table A or B\n"
                  "carrying rotary table C) and xyza (a rotary table A about x). M428 / G43.4 switch\n"
                  "tool centre point control on (X Y Z are the tip in the part frame), M429 / G49 off\n"
                  "(X Y Z are joints; the tip's path is carried by the tables). The file form is in\n"
                  "the README");
    c->add_option("--start", a.start, kStartHelp);
    c->add_option("--mesher", a.mesher,
                  "dexel: the surface placed from the dexels' exact crossings and normals, sharp edges kept;\n"
                  "vdb: OpenVDB's volumeToMesh on the level set alone")
        ->capture_default_str();
    c->add_option("--refine", a.refineRounds,
                  "Rounds of refinement against the exact part (catches cusps finer than the spacing):\n"
                  "vertices and edge midpoints off it move to, or are split at, the surface the moves'\n"
                  "sweeps cut there. 0 keeps the mesher's mesh. Needs a box stock; costs time")
        ->check(numberCheck(true))
        ->check(CLI::Range(0, 8))
        ->capture_default_str();
    c->add_option("--refine-tolerance", a.refineTolerance,
                  "Refinement splits an edge whose midpoint lies farther than this off the exact part\n"
                  "(in spacings)")
        ->check(numberCheck(false))
        ->capture_default_str();
    c->add_option("--threads", a.threads,
                  "Worker threads for every stage; 0 uses every core. More than the machine runs at once\n"
                  "(its cores, within the process's CPU affinity and quota) are cut to that, with a warning")
        ->check(numberCheck(true))
        ->capture_default_str();
    c->add_option("--max-memory", a.maxMemory,
                  "The most memory the job may use, e.g. 4G or 512M. Default: the least of ulimit -v, the\n"
                  "cgroup's limit and the memory available; a job that will not fit stops before it starts");
    c->add_flag("-q,--quiet", a.quiet, "No progress bar and no warnings on stderr; only the final summary");
}

CLI::App* addSimulate(CLI::App& app, SimulateArgs& a) {
    CLI::App* c = app.add_subcommand(
        "simulate",
        "Cut the stock with the programs and write the part.\n"
        "Inputs are a CAMotics .camotics project or G-code / APT CL programs run in order.");
    addJobOptions(*c, a, true);
    c->add_option("--resolution", a.resolution,
                  "Lattice spacing in mm, at most half the stock's thinnest side. Default: chosen from the stock, "
                  "and printed.")
        ->check(numberCheck(false));
    c->add_option("--families", a.families, "Dexel families to keep: xyz, z, x, y, xy, xz or yz")
        ->capture_default_str();
    c->add_option("-o,--output", a.output,
                  "Mesh of the part: PART.obj, PART.stl or PART.ply (binary STL to a device or pipe\n"
                  "otherwise named, as /dev/stdout)");
    c->add_option("--vdb", a.vdb, "The part as an OpenVDB level set, PART.vdb");
    c->add_option("--png", a.png,
                  "A shaded isometric picture of the part, PART.png; with --design, coloured by the\n"
                  "distance to the design, with a legend in mm");
    c->add_option("--report", a.report, "A JSON report: volumes, collisions, warnings, timings");
    c->add_option("--design", a.design,
                  "The design part, PART.stl (closed) or PART.vdb (a level set), in the program's frame:\n"
                  "every move that removes material it keeps is checked, and those cutting deeper than\n"
                  "--gouge-tolerance are reported as gouges, by file and line; stock left outside it is\n"
                  "reported as excess, and the machined surface is measured against it");
    c->add_option("--design-transform", a.designTransform,
                  "Places a design drawn in another frame: TX,TY,TZ (mm), or the rows of a 3 x 4 matrix\n"
                  "[M | T], M11,M12,M13,TX,M21,M22,M23,TY,M31,M32,M33,TZ: p -> M p + T");
    c->add_option("--gouge-tolerance", a.gougeTolerance,
                  "A move gouges when it removes design material farther than this inside the design's\n"
                  "surface (mm)")
        ->check(numberCheck(true))
        ->capture_default_str();
    c->add_option("--excess-tolerance", a.excessTolerance,
                  "After the cut, stock left farther than this outside the design is excess: its volume,\n"
                  "largest thickness and regions are reported (mm)")
        ->check(numberCheck(true))
        ->capture_default_str();
    c->add_option("--gouge-csv", a.gougeCsv,
                  "The gouges as GOUGES.csv, deepest first: move (counted from 1, as on the console and in\n"
                  "the report), file, line, tool, depth_mm, volume_mm3, x, y, z, rapid (needs --design)");
    c->add_option("--deviation-ply", a.deviationPly,
                  "The part's mesh as DEVIATION.ply, each vertex coloured by its signed distance to the\n"
                  "design (red: inside it, a gouge; green: within tolerance; blue: excess) and carrying\n"
                  "it as the property deviation_mm (needs --design)");
    c->add_option("--adaptivity", a.adaptivity,
                  "Merging of flat regions, from 0 (none) to 1 (triangles within 15 degrees merge,\n"
                  "moving the surface by at most 0.05 spacings); the mesh stays closed. With --mesher vdb,\n"
                  "OpenVDB's own, which moves the surface without a bound (a warning says so)")
        ->check(numberCheck(true))
        ->capture_default_str();
    c->add_flag("--sharp-edges", a.sharpEdges,
                "Kept for old scripts: the dexel mesher always places sharp edges and corners from the\n"
                "exact dexel crossings");
    return c;
}

int runSimulate(const SimulateArgs& args) {
    SimulateOptions options = toOptions(args);
    std::FILE* const summary =
        summaryStream({args.output, args.vdb, args.png, args.report, args.gougeCsv, args.deviationPly});
    ProgressBar bar(!args.quiet && ProgressBar::stderrIsTerminal());
    options.progress = [&bar](const char* stage, std::size_t done, std::size_t total) {
        bar.update(stage, done, total);
    };
    const SimulateReport r = simulate(options);
    bar.finish();

    if (!args.quiet) {
        if (r.resolutionChosen)
            std::cerr << "dexelmill: lattice spacing " << r.resolutionMm << " mm (chosen from the stock; set --resolution)\n";
        std::size_t shown = 0, notes = 0;
        for (const ReportWarning& w : r.warnings) {
            const bool note = w.severity == Diagnostic::Severity::Note;
            if (shown++ >= kPrintedDiagnostics) {
                notes += note;
                continue;
            }
            std::cerr << where(w.where) << (note ? ": note: " : ": warning: ") << printable(w.message) << "\n";
        }
        if (r.warnings.size() > kPrintedDiagnostics) {
            const std::size_t more = r.warnings.size() - kPrintedDiagnostics;
            std::cerr << "dexelmill: " << moreDiagnostics(more - notes, notes)
                      << (args.report.empty() ? "" : " in " + args.report) << "\n";
        }
        shown = 0;
        for (const ReportCollision& c : r.collisions) {
            if (shown++ == kPrintedDiagnostics) break;
            std::fprintf(stderr, "%s: collision: %s move %zu removes %s\n", where(c.where).c_str(),
                         c.kind.c_str(), c.move, volumeText(c.volumeMm3).c_str());
        }
        if (r.collisions.size() > kPrintedDiagnostics)
            std::cerr << "dexelmill: " << r.collisions.size() - kPrintedDiagnostics << " more collisions\n";
        shown = 0;
        for (const ReportGouge& g : r.gouges) {
            if (shown++ == kPrintedDiagnostics) break;
            std::fprintf(stderr, "%s: gouge: %smove %zu (T%d) cuts %s mm into the design, %s, deepest at (%.4f, %.4f, %.4f)\n",
                         where(g.where).c_str(), g.rapid ? "rapid " : "", g.move, g.tool,
                         lengthText(g.depthMm).c_str(), volumeText(g.volumeMm3).c_str(), g.point.x, g.point.y, g.point.z);
        }
        if (r.gouges.size() > kPrintedDiagnostics)
            std::cerr << "dexelmill: " << r.gouges.size() - kPrintedDiagnostics << " more gouges\n";
        shown = 0;
        for (const SimulateReport::ExcessRegion& e : r.excessRegions) {
            if (shown++ == kPrintedDiagnostics) break;
            std::fprintf(stderr,
                         "dexelmill: excess: %s up to %s mm thick (at %.4f, %.4f, %.4f) in x %s .. %s, "
                         "y %s .. %s, z %s .. %s mm\n",
                         volumeText(e.volumeMm3).c_str(), lengthText(e.thicknessMm).c_str(), e.point.x, e.point.y, e.point.z,
                         lengthText(e.box.lo.x).c_str(), lengthText(e.box.hi.x).c_str(), lengthText(e.box.lo.y).c_str(),
                         lengthText(e.box.hi.y).c_str(), lengthText(e.box.lo.z).c_str(), lengthText(e.box.hi.z).c_str());
        }
        if (r.surfaceDeviation) printDeviation(*r.surfaceDeviation);
    }
    const double pct = r.stockVolumeMm3 > 0 ? 100.0 * r.removedVolumeMm3 / r.stockVolumeMm3 : 0.0;
    std::string meshState;
    if (r.meshTriangles) {
        meshState = r.meshClosed ? " (closed" : " (NOT closed";
        meshState += r.meshFoldedTriangles ? ", " + std::to_string(r.meshFoldedTriangles) + " folded)" : ")";
    }
    std::string gouges;
    if (!r.designFile.empty()) {
        char text[320];
        std::snprintf(text, sizeof text,
                      "%s (deepest %s mm, tolerance %s mm), excess %s outside the design "
                      "(thickest %s mm, tolerance %s mm), ",
                      counted(r.gouges.size(), "gouge").c_str(),
                      lengthText(r.gouges.empty() ? 0.0 : r.gouges.front().depthMm).c_str(),
                      lengthText(r.gougeToleranceMm).c_str(), volumeText(r.excessVolumeMm3).c_str(),
                      lengthText(r.excessThicknessMm).c_str(), lengthText(r.excessToleranceMm).c_str());
        gouges = text;
    }
    const std::string moves = counted(r.moves, "move") +
                              (r.movesNotSimulated > 0 ? " (" + std::to_string(r.movesNotSimulated) +
                                                             " more not simulated: unknown position)"
                                                       : "");
    const std::size_t notes = std::size_t(std::count_if(r.warnings.begin(), r.warnings.end(), [](const ReportWarning& w) {
        return w.severity == Diagnostic::Severity::Note;
    }));
    const std::string said =
        counted(r.warnings.size() - notes, "warning") + (notes > 0 ? ", " + counted(notes, "note") : std::string());
    std::fprintf(
        summary, "dexelmill: %s, %s; removed %s (%.1f %% of the stock), part %s; h %.4g mm; %s, %s%s; "
        "mesh %s%s; %.2f s, %.0f MiB\n",
        moves.c_str(), counted(r.toolChanges, "tool change").c_str(), volumeText(r.removedVolumeMm3).c_str(), pct,
        volumeText(r.finalVolumeMm3).c_str(), r.resolutionMm, counted(r.collisions.size(), "collision").c_str(), gouges.c_str(),
        said.c_str(), counted(r.meshTriangles, "triangle").c_str(),
        meshState.c_str(), r.timingS.total, r.peakMemoryMb);
    return 0;
}

}  // namespace dexelmill::cli
