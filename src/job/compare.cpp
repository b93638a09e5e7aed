// The compare job: a machined part read from a file, measured against the design.
#include "dexelmill/job/compare.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include <tbb/task_arena.h>

#include "dexelmill/compare/design.h"
#include "dexelmill/decimal.h"
#include "dexelmill/error.h"
#include "dexelmill/io/atomic_file.h"
#include "dexelmill/io/file_name.h"
#include "dexelmill/io/mesh_io.h"
#include "dexelmill/io/vdb_io.h"
#include "dexelmill/job/memory.h"
#include "dexelmill/job/report_format.h"
#include "dexelmill/surface/levelset.h"
#include "job/detail/deviation_files.h"
#include "job/detail/deviation_json.h"

namespace dexelmill {

namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

void validate(const CompareOptions& o) {
    const std::string machined = lowerExtension(o.machinedPath);
    if (machined != ".stl" && machined != ".vdb")
        throw Error("'" + o.machinedPath + "': the machined part must be an STL file (.stl) or a level set (.vdb)");
    for (double t : {o.tolerance.gouge, o.tolerance.excess})
        if (!(t >= 0.0) || !std::isfinite(t)) throw Error("the tolerances must be finite distances of 0 mm or more");
    if (!o.plyPath.empty() && !takesFormat(o.plyPath, ".ply"))
        throw Error("output '" + o.plyPath + "': the deviation mesh is written as .ply");
    if (!o.pngPath.empty() && !takesFormat(o.pngPath, ".png"))
        throw Error("output '" + o.pngPath + "': a picture is written as .png");
    if (!o.reportPath.empty() && !takesFormat(o.reportPath, ".json"))
        throw Error("output '" + o.reportPath + "': the report is written as .json");
    checkSeparateFiles({{"MACHINED", o.machinedPath}, {"DESIGN", o.designPath}},
                       {{"--ply", o.plyPath}, {"--png", o.pngPath}, {"--report", o.reportPath}});
    // A folder that is missing or not writable is found now, not after the measurement.
    for (const std::string* path : {&o.plyPath, &o.pngPath, &o.reportPath})
        if (!path->empty()) checkWritable(*path);
}

CompareReport compareInArena(const CompareOptions& o) {
    const auto tStart = Clock::now();
    validate(o);
    CompareReport r;
    r.version = DEXELMILL_VERSION;
    r.machinedFile = o.machinedPath;
    r.designFile = o.designPath;

    auto t = Clock::now();
    const Mesh machined =
        lowerExtension(o.machinedPath) == ".stl" ? readStl(o.machinedPath) : meshLevelSet(readVdb(o.machinedPath));
    if (machined.empty()) throw Error("'" + o.machinedPath + "': the machined part has no surface");
    const MeshCheck check = checkMesh(machined);
    r.machinedVertices = machined.vertices.size();
    r.machinedTriangles = machined.triangles.size();
    r.machinedClosed = check.closedManifold();
    std::optional<MeshDistance> design;
    {
        const Mesh mesh = readDesign(o.designPath, o.designTransform);
        r.designTriangles = mesh.triangles.size();
        const MeshCheck designCheck = checkMesh(mesh);
        r.designClosed = designCheck.closedManifold();
        if (!r.designClosed)
            r.warnings.push_back("'" + o.designPath + "': the design is not closed (" + designCheck.openness() +
                                 "): which side of it is inside is a guess near the gaps, and so is the sign of "
                                 "the deviation there");
        design.emplace(mesh);
    }
    r.timingS.read = seconds(t);

    t = Clock::now();
    Deviation deviation = measureDeviation(machined, *design, o.tolerance);
    r.timingS.measure = seconds(t);

    // Every file is staged, and renamed only once all are written.
    t = Clock::now();
    OutputBatch outputs;
    std::vector<double> distance = std::move(deviation.distance);
    deviation.distance = {};
    // The picture and the PLY colour the vertices; the figures count the points inside the
    // triangles too. Where those alone leave the tolerance, the colours cannot show it.
    if (!distance.empty() && (!o.pngPath.empty() || !o.plyPath.empty())) {
        const auto [lowest, highest] = std::minmax_element(distance.begin(), distance.end());
        const bool gougeHidden = deviation.deepest < -o.tolerance.gouge && *lowest >= -o.tolerance.gouge;
        const bool excessHidden = deviation.farthest > o.tolerance.excess && *highest <= o.tolerance.excess;
        const auto hidden = [&](const std::string& what, double mm) {
            r.warnings.push_back("the " + what + " found between the mesh's vertices (up to " + lengthText(mm) +
                                 " mm) does not show in the picture and the PLY, which colour the vertices: the "
                                 "mesh's triangles are larger than what they miss");
        };
        if (gougeHidden) hidden("gouge", -deviation.deepest);
        if (excessHidden) hidden("excess", deviation.farthest);
    }
    writeDeviationFiles(machined, deviation, std::move(distance), o.pngPath, o.plyPath, outputs);
    r.deviation = std::move(deviation);
    r.timingS.write = seconds(t);
    r.timingS.total = seconds(tStart);
    r.peakMemoryMb = peakMemoryMb();
    if (!o.reportPath.empty()) {
        const std::string text = compareJson(r);
        writeStreamAtomically(o.reportPath, [&](std::ostream& out) { out << text; }, &outputs);
    }
    outputs.commit();
    return r;
}

}  // namespace

CompareReport compareParts(const CompareOptions& o) {
    tbb::task_arena arena(arenaThreads(o.threads));
    return arena.execute([&] { return compareInArena(o); });
}

std::string compareJson(const CompareReport& r) {
    nlohmann::json j;
    j["format"] = kReportFormat;
    j["version"] = r.version;
    j["units"] = "mm";
    j["machined"] = {{"file", r.machinedFile},
                     {"vertices", r.machinedVertices},
                     {"triangles", r.machinedTriangles},
                     {"closed", r.machinedClosed}};
    j["design"] = {{"file", r.designFile}, {"triangles", r.designTriangles}, {"closed", r.designClosed}};
    j["warnings"] = r.warnings;
    j["surface"] = deviationJson(r.deviation);
    j["timing_s"] = {{"read", r.timingS.read}, {"measure", r.timingS.measure}, {"write", r.timingS.write},
                     {"total", r.timingS.total}};
    j["peak_memory_mb"] = r.peakMemoryMb;
    return j.dump(2) + "\n";
}

}  // namespace dexelmill
