/// @file compare.h
/// @brief The compare job: an existing machined part (a mesh or a level set) measured against the
/// design, with no program and so no move to blame: the deviation's statistics, a coloured PLY, a
/// coloured picture and a JSON report. `dexelmill compare` is a thin layer over this.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "dexelmill/compare/deviation.h"
#include "dexelmill/geometry/affine.h"

namespace dexelmill {

/// @brief What a comparison reads and writes.
struct CompareOptions {
    /// The machined part: a closed STL, or a VDB level set (meshed at its voxel size).
    std::string machinedPath;
    /// The design: a closed STL or a VDB level set, placed by `designTransform` when given.
    std::string designPath;
    std::optional<Affine> designTransform;
    DeviationTolerance tolerance;
    /// Outputs; empty paths are not written: the machined mesh coloured by deviation (.ply, with
    /// the property deviation_mm), its picture with a legend (.png), the report (.json).
    std::string plyPath, pngPath, reportPath;
    /// Worker threads; 0 uses every core.
    int threads = 0;
};

/// @brief What a comparison found.
struct CompareReport {
    std::string version, machinedFile, designFile;
    std::size_t machinedVertices = 0, machinedTriangles = 0, designTriangles = 0;
    bool machinedClosed = false;
    /// Whether the design's mesh is closed (checkMesh). Where it is open, which side of it is
    /// inside is a guess, and so is the sign of the deviation near the gap.
    bool designClosed = false;
    /// What the user should know of the inputs: an open design.
    std::vector<std::string> warnings;
    /// The machined surface against the design, without its per-vertex distances.
    Deviation deviation;
    struct Timing {
        double read = 0, measure = 0, write = 0, total = 0;
    } timingS;
    double peakMemoryMb = 0.0;
};

/// @brief Reads both parts, measures every vertex of the machined mesh against the design
/// (measureDeviation) and writes the requested files.
/// @throw Error for unreadable inputs, bad tolerances or unwritable outputs (these before any
/// work); no output is then left half-written, and no existing file is replaced: the files are
/// renamed together once all are written (OutputBatch).
CompareReport compareParts(const CompareOptions& options);

/// @brief The report as JSON text (snake_case, units in the names).
std::string compareJson(const CompareReport& report);

}  // namespace dexelmill
