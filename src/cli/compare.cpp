// `dexelmill compare`: a machined part read from a file against the design.
#include <cmath>
#include <cstdio>
#include <string>

#include "commands.h"
#include "dexelmill/decimal.h"
#include "dexelmill/job/compare.h"

namespace dexelmill::cli {

CLI::App* addCompare(CLI::App& app, CompareArgs& a) {
    CLI::App* c = app.add_subcommand(
        "compare",
        "Measures a machined part (a mesh or a level set, e.g. from 'simulate -o' or '--vdb') against\n"
        "the design, at its vertices and at points inside its triangles (the spacing is printed):\n"
        "how much of its surface lies within tolerance, how deep it cuts into the design\n"
        "and how far it stays outside, as a histogram; with a coloured PLY and picture. Without a\n"
        "program no move is named: 'simulate --design' does that.");
    c->add_option("MACHINED", a.machined, "The machined part: PART.stl or PART.vdb (whether its mesh is closed is\nreported)")->required();
    c->add_option("DESIGN", a.design, "The design: DESIGN.stl (closed) or DESIGN.vdb, in the same frame")->required();
    c->add_option("--design-transform", a.designTransform,
                  "Places a design drawn in another frame: TX,TY,TZ (mm), or the rows of a 3 x 4 matrix\n"
                  "[M | T], M11,M12,M13,TX,M21,M22,M23,TY,M31,M32,M33,TZ: p -> M p + T");
    c->add_option("--gouge-tolerance", a.gougeTolerance,
                  "Surface farther than this inside the design is gouged (mm)")
        ->check(numberCheck(true))
        ->capture_default_str();
    c->add_option("--excess-tolerance", a.excessTolerance,
                  "Surface farther than this outside the design is excess (mm)")
        ->check(numberCheck(true))
        ->capture_default_str();
    c->add_option("--ply", a.ply,
                  "The machined mesh as DEVIATION.ply, each vertex coloured by its signed distance to the\n"
                  "design (red: inside it; green: within tolerance; blue: outside) and carrying it as\n"
                  "the property deviation_mm");
    c->add_option("--png", a.png, "A picture of the machined part in the same colours, with a legend in mm");
    c->add_option("--report", a.report, "A JSON report: areas by tolerance, extremes, RMS and the histogram");
    c->add_option("--threads", a.threads, "Worker threads; 0 uses every core. More than the machine runs at once are cut to that, with a warning")
        ->check(numberCheck(true))
        ->capture_default_str();
    return c;
}

int runCompare(const CompareArgs& a) {
    CompareOptions o;
    o.machinedPath = a.machined;
    o.designPath = a.design;
    if (!a.designTransform.empty()) o.designTransform = parseTransform(a.designTransform);
    o.tolerance = {a.gougeTolerance, a.excessTolerance};
    o.plyPath = a.ply;
    o.pngPath = a.png;
    o.reportPath = a.report;
    o.threads = a.threads;
    warnThreads(a.threads);
    std::FILE* const out = summaryStream({a.ply, a.png, a.report});
    const CompareReport r = compareParts(o);
    for (const std::string& w : r.warnings) std::fprintf(stderr, "dexelmill: warning: %s\n", printable(w).c_str());
    const Deviation& d = r.deviation;
    // Lengths and areas print without exponents (decimal.h); a range's ends carry their sign.
    std::fprintf(out, "dexelmill: %s (%zu triangles%s) against %s (%zu triangles%s), tolerances -%s / +%s mm\n",
                r.machinedFile.c_str(), r.machinedTriangles, r.machinedClosed ? "" : ", NOT closed",
                r.designFile.c_str(), r.designTriangles, r.designClosed ? "" : ", NOT closed",
                lengthText(d.tolerance.gouge).c_str(), lengthText(d.tolerance.excess).c_str());
    std::fprintf(out, "  measured at the vertices and at points inside the triangles: every point of the surface lies\n"
                "  within %s mm of a measured one\n",
                lengthText(d.spacing / std::sqrt(3.0)).c_str());
    std::fprintf(out, "  %-22s %14s %8s %10s\n", "deviation (mm)", "area (mm^2)", "area %", "points");
    for (const DeviationBin& b : d.histogram) {
        const std::string range = signedLengthText(b.lo) + " .. " + signedLengthText(b.hi);
        std::fprintf(out, "  %-22s %14s %8.2f %10zu%s\n", range.c_str(), areaText(b.area).c_str(),
                    d.area > 0 ? 100.0 * b.area / d.area : 0.0, b.points,
                    b.lo == -d.tolerance.gouge && b.hi == d.tolerance.excess ? "  within tolerance" : "");
    }
    std::fprintf(out, "  deepest %s mm into the design at (%.4f, %.4f, %.4f); farthest %s mm outside at "
                "(%.4f, %.4f, %.4f); RMS %s mm; %.2f s, %.0f MiB\n",
                lengthText(d.deepest < 0.0 ? -d.deepest : 0.0).c_str(), d.deepestPoint.x, d.deepestPoint.y, d.deepestPoint.z,
                lengthText(d.farthest).c_str(), d.farthestPoint.x, d.farthestPoint.y, d.farthestPoint.z, lengthText(d.rms).c_str(),
                r.timingS.total, r.peakMemoryMb);
    return 0;
}

}  // namespace dexelmill::cli
