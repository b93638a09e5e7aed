#include "job/detail/deviation_files.h"

#include <utility>

#include "dexelmill/io/mesh_io.h"
#include "dexelmill/io/picture.h"

namespace dexelmill {

void writeDeviationFiles(const Mesh& mesh, const Deviation& deviation, std::vector<double> distance,
                         const std::string& pngPath, const std::string& plyPath, OutputBatch& batch) {
    if (pngPath.empty() && plyPath.empty()) return;
    const DeviationScale scale = deviationScale(deviation);
    PlyVertexData data;
    data.colours = deviationColours(distance, scale);
    if (!pngPath.empty()) {
        const PictureLegend legend = deviationLegend(scale);
        PictureOptions picture;
        picture.vertexColours = &data.colours;
        picture.legend = &legend;
        writePicture(pngPath, mesh, picture, &batch);
    }
    if (!plyPath.empty()) {
        data.scalarName = "deviation_mm";
        data.scalar = std::move(distance);
        writePly(plyPath, mesh, data, &batch);
    }
}

}  // namespace dexelmill
