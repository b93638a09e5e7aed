// `dexelmill study`: run the job per (spacing, family set) and measure against the exact part.
#include <algorithm>
#include <cstdio>
#include <iostream>

#include "commands.h"
#include "dexelmill/decimal.h"
#include "dexelmill/study/study.h"
#include "progress.h"

namespace dexelmill::cli {

CLI::App* addStudy(CLI::App& app, StudyArgs& a) {
    std::string names;
    for (const std::string& n : studyCaseNames()) names += (names.empty() ? "" : ", ") + n;
    CLI::App* c = app.add_subcommand(
        "study",
        "Accuracy study: run the job once per (spacing, family set) and measure each result against the\n"
        "exact machined part (brute-force membership): surface deviation (max, RMS, 95th percentile, in mm\n"
        "and in spacings) and material lost or invented; and the volume error, against the exact volume\n"
        "where the case knows it, else against a tri-dexel run at half the finest spacing.");
    addJobOptions(*c, a.job, false);
    c->get_option("--stock")->description(
        "box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX (mm); the exact part is measured from a box stock only.\n"
        "Default: the case's or the project's workpiece, else the program's extent.");
    c->add_option("--case", a.caseName, "A built-in case instead of a program: " + names);
    c->add_option("--resolutions", a.resolutions, "Lattice spacings in mm, comma-separated")->capture_default_str();
    c->add_option("--families", a.familySets, "Family sets to compare, comma-separated (z, xyz, x, xy, ...)")
        ->capture_default_str();
    c->add_option("--csv", a.csv, "One row per (spacing, family set)");
    c->add_option("--plot", a.plot, "Log-log PNG plot of deviation (away from the stock's faces) against spacing");
    c->add_option("--ply-deviation", a.plyDir, "Folder for PLY meshes coloured by deviation, one per run");
    c->add_option("--surface-points", a.surfacePoints,
                  "Points measured per run, spread evenly over the mesh's triangles")
        ->check(numberCheck(false))
        ->capture_default_str();
    c->add_option("--samples", a.samples, "Random points for the lost / invented material counts")
        ->check(numberCheck(false))
        ->capture_default_str();
    return c;
}

int runStudy(const StudyArgs& a) {
    StudyOptions o;
    if (a.caseName.empty() == a.job.inputs.empty())
        throw UsageError("study: give either a program (or project) or --case NAME");
    o.job = toOptions(a.job);
    if (!a.caseName.empty()) {
        // The case's exact part is its own program's with its own tools: another tool would be
        // dropped without a word.
        if (o.job.defaultTool || !o.job.tools.empty() || !o.job.toolTable.empty())
            throw UsageError(std::string(o.job.toolTable.empty() ? "--tool" : "--tool-table") +
                             ": a --case cuts with its own tools; to study another tool, write the program "
                             "and give it with --tool");
        StudyCase c;
        try {
            c = studyCase(a.caseName);
        } catch (const Error& e) {
            throw UsageError(std::string("--case: ") + e.what());
        }
        o.job.program = std::move(c.program);
        if (!o.job.stockBox && !o.job.stockFrustum && o.job.stockFile.empty()) o.job.stockBox = c.stock;
        o.job.inputs = {"case:" + c.name};
    }
    // The study runs each spacing and each family set once: one listed again is said, not dropped.
    const auto listedAgain = [&a](const char* option, const std::string& item) {
        if (!a.job.quiet)
            std::fprintf(stderr, "dexelmill: warning: %s lists %s more than once; it runs once\n", option,
                         item.c_str());
    };
    o.resolutions.clear();
    for (const std::string& r : splitAtCommas(a.resolutions)) {
        const std::optional<double> h = parseDecimal(r);
        if (!h || !(*h > 0)) throw UsageError("--resolutions: '" + r + "' is not a positive number");
        if (std::find(o.resolutions.begin(), o.resolutions.end(), *h) != o.resolutions.end())
            listedAgain("--resolutions", r + " mm");
        o.resolutions.push_back(*h);
    }
    o.familySets.clear();
    for (const std::string& f : splitAtCommas(a.familySets)) {
        FamilySet set;
        try {
            set = FamilySet::parse(f);
        } catch (const Error& e) {
            throw UsageError(std::string("--families: ") + e.what());
        }
        if (std::any_of(o.familySets.begin(), o.familySets.end(), [&](FamilySet g) { return g.mask == set.mask; }))
            listedAgain("--families", set.str());
        o.familySets.push_back(set);
    }
    if (o.resolutions.empty() || o.familySets.empty()) throw UsageError("study: --resolutions and --families need values");
    o.surfacePoints = a.surfacePoints;
    o.samplePoints = a.samples;
    o.plyDeviationDir = a.plyDir;
    o.csvPath = a.csv;
    o.plotPath = a.plot;
    if (!a.job.quiet) warnThreads(a.job.threads);
    ProgressBar bar(!a.job.quiet && ProgressBar::stderrIsTerminal());
    o.progress = [&bar](const char* stage, std::size_t done, std::size_t total) { bar.update(stage, done, total); };
    std::FILE* const out = summaryStream({a.csv, a.plot});
    const StudyResult r = runStudy(o);
    bar.finish();
    std::fprintf(out, "study of %s; reference volume %s (%s)\n", r.subject.c_str(), volumeText(r.referenceVolumeMm3).c_str(),
                r.reference.c_str());
    std::fprintf(out, "deviations in mm at points over the mesh; 'inner': those at least one spacing from the stock's faces\n");
    std::fprintf(out, "%8s %-8s %11s %11s %11s %11s %11s %11s %13s %10s %13s %8s\n", "h_mm", "families", "max", "rms",
                "p95", "inner_max", "inner_rms", "inner_p95", "vol_err_mm3", "lost_mm3", "invented_mm3", "time_s");
    for (const StudyRun& x : r.runs)
        std::fprintf(out, "%8.4g %-8s %11.4g %11.4g %11.4g %11.4g %11.4g %11.4g %13.5g %10.4g %13.4g %8.3f\n", x.h,
                    x.families.c_str(), x.devMaxMm, x.devRmsMm, x.devP95Mm, x.innerMaxMm, x.innerRmsMm,
                    x.innerP95Mm, x.volumeErrorMm3, x.lostMm3, x.inventedMm3, x.seconds);
    return 0;
}

}  // namespace dexelmill::cli
