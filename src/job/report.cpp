#include <cmath>
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "dexelmill/job/report_format.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/stock/lattice.h"
#include "job/detail/deviation_json.h"

namespace dexelmill {

nlohmann::json deviationJson(const Deviation& d) {
    using nlohmann::json;
    json bins = json::array();
    for (const DeviationBin& b : d.histogram)
        bins.push_back({{"from_mm", b.lo}, {"to_mm", b.hi}, {"area_mm2", b.area}, {"points", b.points}});
    return {{"gouge_tolerance_mm", d.tolerance.gouge},
            {"excess_tolerance_mm", d.tolerance.excess},
            {"sample_spacing_mm", d.spacing},
            {"area_mm2", d.area},
            {"gouge_area_mm2", d.gougeArea},
            {"within_tolerance_area_mm2", d.withinArea},
            {"excess_area_mm2", d.excessArea},
            {"rms_mm", d.rms},
            {"deepest_mm", d.deepest},
            {"deepest_point_mm", {d.deepestPoint.x, d.deepestPoint.y, d.deepestPoint.z}},
            {"farthest_mm", d.farthest},
            {"farthest_point_mm", {d.farthestPoint.x, d.farthestPoint.y, d.farthestPoint.z}},
            {"histogram", bins}};
}

namespace {

nlohmann::json stretchesJson(const FineStretches& s) {
    nlohmann::json regions = nlohmann::json::array();
    for (const FineRegion& r : s.regions)
        regions.push_back({{"volume_mm3", r.volumeMm3},
                           {"box_mm",
                            {{"min", {r.box.lo.x, r.box.lo.y, r.box.lo.z}}, {"max", {r.box.hi.x, r.box.hi.y, r.box.hi.z}}}},
                           {"widest_mm", r.widestMm},
                           {"widest_at_mm", {r.widestAt.x, r.widestAt.y, r.widestAt.z}},
                           {"stretches", r.stretches}});
    return {{"stretches", s.count},
            {"volume_mm3", s.volumeMm3},
            {"widest_mm", s.widestMm},
            {"widest_at_mm", {s.widestAt.x, s.widestAt.y, s.widestAt.z}},
            {"places", s.regionCount},
            {"regions", regions}};
}

}  // namespace

std::string reportJson(const SimulateReport& r) {
    using nlohmann::json;
    json j;
    j["format"] = kReportFormat;
    j["version"] = r.version;
    j["inputs"] = r.inputs;
    j["units"] = "mm";
    j["resolution_mm"] = r.resolutionMm;
    j["resolution_chosen"] = r.resolutionChosen;
    j["families"] = r.families;
    j["stock_box_mm"] = {{"min", {r.stockBox.lo.x, r.stockBox.lo.y, r.stockBox.lo.z}},
                         {"max", {r.stockBox.hi.x, r.stockBox.hi.y, r.stockBox.hi.z}}};
    j["moves"] = r.moves;
    j["rapids"] = r.rapids;
    j["moves_not_simulated"] = r.movesNotSimulated;
    j["tool_changes"] = r.toolChanges;
    j["lattice"] = {{"nx", r.lattice[0]}, {"ny", r.lattice[1]}, {"nz", r.lattice[2]}};
    j["dexels"] = {{"x", r.dexels[0]}, {"y", r.dexels[1]}, {"z", r.dexels[2]}};
    j["stock_volume_mm3"] = r.stockVolumeMm3;
    j["final_volume_mm3"] = r.finalVolumeMm3;
    j["removed_volume_mm3"] = r.removedVolumeMm3;
    json fam = json::object();
    for (int a = 0; a < 3; ++a)
        if (r.familyVolumesMm3[a]) fam[std::string(1, axisName(axisFromIndex(a)))] = *r.familyVolumesMm3[a];
    j["family_volumes_mm3"] = fam;
    j["finer_than_lattice"] = {{"material", stretchesJson(r.fineFeatures.material)},
                               {"gaps", stretchesJson(r.fineFeatures.gaps)}};
    json collisions = json::array();
    for (const ReportCollision& c : r.collisions)
        collisions.push_back({{"move", c.move},
                              {"file", c.where.file},
                              {"line", c.where.line},
                              {"kind", c.kind},
                              {"volume_mm3", c.volumeMm3}});
    j["collisions"] = collisions;
    if (!r.designFile.empty()) {
        json gouges = json::array();
        for (const ReportGouge& g : r.gouges)
            gouges.push_back({{"move", g.move},
                              {"file", g.where.file},
                              {"line", g.where.line},
                              {"tool", g.tool},
                              {"rapid", g.rapid},
                              {"depth_mm", g.depthMm},
                              {"volume_mm3", g.volumeMm3},
                              {"point_mm", {g.point.x, g.point.y, g.point.z}}});
        json regions = json::array();
        for (const SimulateReport::ExcessRegion& e : r.excessRegions)
            regions.push_back({{"min_mm", {e.box.lo.x, e.box.lo.y, e.box.lo.z}},
                               {"max_mm", {e.box.hi.x, e.box.hi.y, e.box.hi.z}},
                               {"volume_mm3", e.volumeMm3},
                               {"thickness_mm", e.thicknessMm},
                               {"thickest_point_mm", {e.point.x, e.point.y, e.point.z}}});
        j["design"] = {{"file", r.designFile},
                       {"closed", r.designClosed},
                       {"gouge_tolerance_mm", r.gougeToleranceMm},
                       {"gouge_count", r.gouges.size()},
                       {"worst_gouge_mm", r.gouges.empty() ? 0.0 : r.gouges.front().depthMm},
                       {"gouges", gouges},
                       {"excess_tolerance_mm", r.excessToleranceMm},
                       {"excess_volume_mm3", r.excessVolumeMm3},
                       {"worst_excess_mm", r.excessThicknessMm},
                       {"worst_excess_point_mm", {r.excessPoint.x, r.excessPoint.y, r.excessPoint.z}},
                       {"excess_regions", regions}};
        if (r.surfaceDeviation) j["design"]["surface"] = deviationJson(*r.surfaceDeviation);
    }
    json warnings = json::array();
    // A warning about the whole run (the stock chosen, a tool not used) has no place: its file,
    // line and column are left out rather than written as "" and 0, and so is what is unknown of
    // a place (a move has a line, a word its column too).
    for (const ReportWarning& w : r.warnings) {
        json entry = json::object();
        if (!w.where.file.empty()) entry["file"] = w.where.file;
        if (w.where.line > 0) entry["line"] = w.where.line;
        if (w.where.line > 0 && w.where.column > 0) entry["column"] = w.where.column;
        entry["message"] = w.message;
        entry["severity"] = w.severity == Diagnostic::Severity::Note ? "note" : "warning";
        warnings.push_back(entry);
    }
    j["warnings"] = warnings;
    j["mesh"] = {{"mesher", r.mesher},
                 {"vertices", r.meshVertices},
                 {"triangles", r.meshTriangles},
                 {"closed", r.meshClosed},
                 {"folded_triangles", r.meshFoldedTriangles},
                 {"degenerate_triangles", r.meshDegenerateTriangles},
                 {"volume_mm3", r.meshVolumeMm3}};
    if (r.mesher == "dexel")
        j["mesh"]["dexel_mesher"] = {{"exact_crossings", r.exactCrossings},
                                     {"interpolated_crossings", r.interpolatedCrossings},
                                     {"edge_vertices", r.edgeVertices},
                                     {"corner_vertices", r.cornerVertices},
                                     {"plain_cells", r.plainCells},
                                     {"edges_with_several_crossings", r.splitEdges},
                                     {"edges_with_several_crossings_left_out", r.splitEdgesDropped},
                                     {"split_cells", r.splitCells},
                                     {"face_vertices", r.faceVertices},
                                     {"patch_pairs_left_crossing", r.patchPairsLeftCrossing},
                                     {"runs", r.meshRuns}};
    if (r.refineRounds > 0)
        j["mesh"]["refine"] = {{"rounds", r.refineRounds},
                               {"points_tested", r.refineQueries},
                               {"vertices_snapped", r.refineSnapped},
                               {"vertices_snapped_part_way", r.refineSnapPartial},
                               {"edges_split", r.refineSplit},
                               {"splits_refused", r.refineRefused},
                               {"crossing_triangles_found", r.refineCrossed},
                               {"midpoints_without_crossing", r.refineNoCrossing},
                               {"nearer_along_another_axis", r.refineLaterAxis},
                               {"short_edges_collapsed", r.refineCollapsed}};
    j["timing_s"] = {{"parse", r.timingS.parse}, {"design", r.timingS.design}, {"cut", r.timingS.cut},     {"rebuild", r.timingS.rebuild},
                     {"mesh", r.timingS.mesh},   {"refine", r.timingS.refine}, {"write", r.timingS.write},
                     {"total", r.timingS.total}};
    j["peak_memory_mb"] = r.peakMemoryMb;
    j["heap_huge_pages"] = r.heapOnHugePages;
    j["threads_started"] = r.threadsStarted;
    j["stock_memory_mb"] = double(r.stockMemoryBytes) / (1024.0 * 1024.0);
    return j.dump(2) + "\n";
}

std::string gougeCsv(const SimulateReport& r) {
    auto quoted = [](const std::string& text) {
        std::string q = "\"";
        for (char c : text) q += c == '"' ? std::string("\"\"") : std::string(1, c);
        return q + "\"";
    };
    std::string out = "move,file,line,tool,depth_mm,volume_mm3,x,y,z,rapid\n";
    char row[256];
    for (const ReportGouge& g : r.gouges) {
        std::snprintf(row, sizeof row, ",%d,%d,%.6f,%.6f,%.6f,%.6f,%.6f,%d\n", g.where.line, g.tool, g.depthMm,
                      g.volumeMm3, g.point.x, g.point.y, g.point.z, g.rapid ? 1 : 0);
        out += std::to_string(g.move) + "," + quoted(g.where.file) + row;
    }
    return out;
}

double chooseResolution(const Box& stock, double cells) {
    const Vec3 s = stock.size();
    const double longest = std::max({s.x, s.y, s.z}), thinnest = std::min({s.x, s.y, s.z});
    const double raw = std::min(longest / cells, thinnest / kMinCellsAcross);
    const double decade = std::pow(10.0, std::floor(std::log10(raw)));
    for (double m : {5.0, 2.0, 1.0})
        if (m * decade <= raw) return m * decade;
    return decade;
}

}  // namespace dexelmill
