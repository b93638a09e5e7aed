// The deviation's files, shared by the simulate and compare jobs.
#pragma once

#include <string>
#include <vector>

#include "dexelmill/compare/deviation.h"
#include "dexelmill/io/atomic_file.h"
#include "dexelmill/surface/mesh.h"

namespace dexelmill {

/// @brief Writes the mesh coloured by its vertices' signed distances (`distance`, one per vertex;
/// the scale from `deviation`'s extremes and tolerances): a picture with a legend at `pngPath`
/// and a PLY with colours and the property deviation_mm at `plyPath`, each when its path is not
/// empty; both staged in `batch`.
void writeDeviationFiles(const Mesh& mesh, const Deviation& deviation, std::vector<double> distance,
                         const std::string& pngPath, const std::string& plyPath, OutputBatch& batch);

}  // namespace dexelmill
