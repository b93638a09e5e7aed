// Meshing of a LevelSet: the one translation unit that includes openvdb/tools/VolumeToMesh.h.
#include <cmath>

#include <openvdb/openvdb.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "dexelmill/error.h"
#include "dexelmill/surface/levelset.h"
#include "dexelmill/surface/levelset_vdb.h"

namespace dexelmill {

Mesh meshLevelSet(const LevelSet& levelSet, const MeshOptions& options) {
    if (!(options.adaptivity >= 0.0 && options.adaptivity <= 1.0))
        throw Error("meshing: adaptivity must lie in [0, 1], got " +
                    std::to_string(options.adaptivity));
    openvdb::FloatGrid::ConstPtr grid = gridOf(levelSet);
    if (!grid) throw Error("meshing: the level set holds no grid");

    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> tris;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(*grid, points, tris, quads, 0.0, options.adaptivity);

    Mesh mesh;
    mesh.vertices.resize(points.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i < r.end(); ++i)
                              mesh.vertices[i] = Vec3(points[i].x(), points[i].y(), points[i].z());
                      });
    std::vector<openvdb::Vec3s>().swap(points);

    // volumeToMesh orients its polygons clockwise seen from outside a level set (negative
    // inside); reverse each polygon so that (b - a) x (c - a) points outward.
    mesh.triangles.resize(tris.size() + 2 * quads.size());
    for (std::size_t t = 0; t < tris.size(); ++t)
        mesh.triangles[t] = {tris[t][2], tris[t][1], tris[t][0]};
    const std::size_t base = tris.size();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, quads.size(), 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t q = r.begin(); q < r.end(); ++q) {
            // Reversed quad a b c d; split along the shorter diagonal.
            const std::uint32_t a = quads[q][3], b = quads[q][2], c = quads[q][1], d = quads[q][0];
            const Vec3 &pa = mesh.vertices[a], &pb = mesh.vertices[b], &pc = mesh.vertices[c],
                       &pd = mesh.vertices[d];
            const double ac = glm::dot(pc - pa, pc - pa), bd = glm::dot(pd - pb, pd - pb);
            Mesh::Triangle* out = &mesh.triangles[base + 2 * q];
            if (ac <= bd) {
                out[0] = {a, b, c};
                out[1] = {a, c, d};
            } else {
                out[0] = {a, b, d};
                out[1] = {b, c, d};
            }
        }
    });
    return mesh;
}

}  // namespace dexelmill
