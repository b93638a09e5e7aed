/// @file study.h
/// @brief Accuracy studies: run the main job once per (spacing, dexel family set) and measure each
/// result against the exact machined solid (MachinedSolidOracle): surface deviation of the mesh (at
/// points spread evenly over its triangles), volume error, and material the model loses or invents.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "dexelmill/io/atomic_file.h"
#include "dexelmill/job/simulate.h"

namespace dexelmill {

/// @brief What to study.
struct StudyOptions {
    /// The job to repeat: program or project, stock, tools. Its resolution, families and output
    /// paths are ignored.
    SimulateOptions job;
    std::vector<double> resolutions{2.0, 1.0, 0.5};  ///< mm, any order
    std::vector<FamilySet> familySets{FamilySet::only(Axis::Z), FamilySet::all()};
    /// Points measured per run on the mesh: uniform over the triangles' area, a fixed seed. (The
    /// dexel mesher's vertices on cell edges are exact crossings: the faces between are what a
    /// person sees and what is measured.)
    std::size_t surfacePoints = 20000;
    /// Random points (fixed seed) for the lost and invented material counts.
    std::size_t samplePoints = 100000;
    /// When set, a PLY mesh coloured by deviation is written per run into this folder (made if
    /// missing).
    std::string plyDeviationDir;
    /// Outputs; empty paths are not written: the table (studyCsv, .csv) and the plot
    /// (writeStudyPlot, .png). They and the deviation meshes are renamed together once all are
    /// written.
    std::string csvPath, plotPath;
    /// Exact part volume when known (mm^3); otherwise a finer tri-dexel run is the reference.
    std::optional<double> exactVolumeMm3;
    std::function<void(const char* stage, std::size_t done, std::size_t total)> progress;
};

/// @brief Measurements of one run.
struct StudyRun {
    double h = 0.0;
    std::string families;
    std::size_t points = 0;  ///< surface points measured (along their triangle's normal)
    double devMaxMm = 0.0, devRmsMm = 0.0, devP95Mm = 0.0;  ///< |signed distance| statistics
    double devMeanMm = 0.0;                                 ///< signed mean (+ = extra material)
    /// The same statistics over the measured points at least one spacing from the stock box's
    /// faces: the machined surfaces, without the block's own edges (which volumeToMesh rounds by
    /// about 0.65 h) and without the rims where a cut meets the stock's faces.
    std::size_t innerPoints = 0;
    double innerMaxMm = 0.0, innerRmsMm = 0.0, innerP95Mm = 0.0;
    double volumeMm3 = 0.0;                                 ///< the model's part volume
    double volumeErrorMm3 = 0.0;                            ///< model minus reference
    /// Sample points in the exact part that the model calls empty, and the reverse, as volumes;
    /// the "far" counts only those more than one spacing from the model's surface (features
    /// lost or invented, not boundary rounding). Points within one spacing of the stock box's
    /// faces are not counted: every family set rounds the block's own edges alike.
    double lostMm3 = 0.0, inventedMm3 = 0.0, lostFarMm3 = 0.0, inventedFarMm3 = 0.0;
    double seconds = 0.0;       ///< the run (cut, rebuild, mesh), not its measurement
    double peakMemoryMb = 0.0;  ///< peak resident memory the run added to the process (MiB)
    double stockMemoryMb = 0.0; ///< the tri-dexel stock's own memory (MiB)
};

struct StudyResult {
    std::string subject;
    double referenceVolumeMm3 = 0.0;
    std::string reference;  ///< "exact" or "tri-dexel at h = ..."
    std::vector<StudyRun> runs;
};

/// @brief Runs and measures every (spacing, family set), then writes the table and the plot.
/// @throw Error as the job does, or if the lists are empty; before any run where an output
/// cannot be written, a count of points is 0, or the points would not fit in the job's memory
/// budget (SimulateOptions::maxMemoryBytes) with what the process holds. No output is then left
/// half-written, and no existing file is replaced.
StudyResult runStudy(const StudyOptions& options);

/// @brief One row per run: h_mm, families, points, dev_max_mm, dev_rms_mm, dev_p95_mm,
/// dev_max_h, dev_rms_h, dev_p95_h, dev_mean_mm, volume_mm3, volume_error_mm3, volume_error_rel,
/// lost_mm3, invented_mm3, lost_far_mm3, invented_far_mm3, seconds, peak_memory_mb, stock_memory_mb,
/// inner_points, inner_max_mm, inner_rms_mm, inner_p95_mm.
std::string studyCsv(const StudyResult& result);

/// @brief A log-log PNG plot of the maximum, 95th percentile and RMS deviation against spacing over
/// the points away from the stock's faces (StudyRun::inner*), one colour per family set (written
/// atomically; staged in `batch` when given).
void writeStudyPlot(const std::string& path, const StudyResult& result, OutputBatch* batch = nullptr);

/// @brief A built-in study case: a program, its tools and stock, made in memory.
struct StudyCase {
    std::string name;
    std::string description;
    Program program;
    Box stock;
};

/// @brief The names of the built-in cases: tilted-slot, bull-undercut, ball-raster, v-carve.
std::vector<std::string> studyCaseNames();
/// @brief Builds a built-in case.
/// @throw Error listing the names if there is no such case.
StudyCase studyCase(const std::string& name);

}  // namespace dexelmill
