// Casting a level set into tri-dexels: the OpenVDB half of voxelize.h.
#include <algorithm>
#include <cmath>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <tbb/parallel_for.h>

#include "dexelmill/error.h"
#include "dexelmill/surface/levelset_vdb.h"
#include "dexelmill/surface/voxelize.h"
#include "surface/detail/tile_fill.h"

namespace dexelmill {

namespace {

/// Marching stops refining a crossing when its bracket is this fraction of a voxel.
constexpr double kCrossingTolerance = 1e-6;
/// The smallest and largest march step, in voxels (the largest is also capped by the band).
constexpr double kMinStep = 0.25;
/// Steps are this fraction of |phi|: phi is a distance estimate, so this cannot jump a crossing.
constexpr double kStepFactor = 0.8;
/// Half the width of the central differences that give a crossing's normal, in voxels.
constexpr double kGradientStep = 0.5;

}  // namespace

Box materialBounds(const LevelSet& levelSet) {
    openvdb::FloatGrid::ConstPtr grid = gridOf(levelSet);
    if (!grid) throw Error("material bounds: the level set holds no grid");
    openvdb::CoordBBox bbox;
    for (auto it = grid->cbeginValueOn(); it; ++it) {
        if (*it < 0.0f) {
            openvdb::CoordBBox item;
            it.getBoundingBox(item);
            bbox.expand(item);
        }
    }
    if (bbox.empty()) return Box::empty();
    const openvdb::Vec3d lo = grid->indexToWorld(bbox.min().asVec3d() - 1.0);
    const openvdb::Vec3d hi = grid->indexToWorld(bbox.max().asVec3d() + 1.0);
    Box box;
    box.expand(Vec3(lo.x(), lo.y(), lo.z()));
    box.expand(Vec3(hi.x(), hi.y(), hi.z()));
    return box;
}

TriDexelStock stockFromLevelSet(const LevelSet& levelSet, const Lattice& lattice,
                                FamilySet families) {
    openvdb::FloatGrid::ConstPtr grid = gridOf(levelSet);
    if (!grid) throw Error("stock from level set: the level set holds no grid");
    TriDexelStock stock(lattice, families);
    const double vs = grid->voxelSize()[0];
    const double maxStep = std::max(kMinStep * vs, double(grid->background()));
    constexpr int kTile = DexelTile::kTile;

    for (int a = 0; a < 3; ++a) {
        const Axis axis = axisFromIndex(a);
        if (!stock.has(axis)) continue;
        DexelFamily& fam = stock.family(axis);
        const double len = lattice.n[a] * lattice.h;
        tbb::parallel_for(0, fam.tilesC(), [&](int tc) {
            // GridSampler keeps a reference to the accessor: it must outlive the sampler.
            const openvdb::FloatGrid::ConstAccessor accessor = grid->getConstAccessor();
            openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor,
                                        openvdb::tools::BoxSampler>
                sampler(accessor, grid->transform());
            detail::TileRowSegments row(tc, fam.nb());
            const int icHi = std::min(fam.nc(), tc * kTile + kTile);
            for (int ic = tc * kTile; ic < icHi; ++ic) {
                for (int ib = 0; ib < fam.nb(); ++ib) {
                    const Line line = stock.dexelLine(axis, ib, ic);
                    auto phi = [&](double v) {
                        const Vec3 p = line.at(v);
                        return double(sampler.wsSample(openvdb::Vec3d(p.x, p.y, p.z)));
                    };
                    // The outward normal at a crossing: the gradient of the interpolated
                    // field, by central differences half a voxel wide.
                    auto normalAt = [&](double v) {
                        const Vec3 p = line.at(v);
                        Vec3 g;
                        for (int k = 0; k < 3; ++k) {
                            openvdb::Vec3d lo(p.x, p.y, p.z), hi = lo;
                            lo[k] -= kGradientStep * vs;
                            hi[k] += kGradientStep * vs;
                            g[k] = double(sampler.wsSample(hi)) - double(sampler.wsSample(lo));
                        }
                        return PackedNormal::pack(g);
                    };
                    std::vector<Segment>& segs = row.at(ib, ic);
                    double v = 0.0, f = phi(v);
                    bool in = f < 0.0;
                    double start = 0.0;
                    while (v < len) {
                        const double step =
                            std::min(maxStep, std::max(kMinStep * vs, kStepFactor * std::abs(f)));
                        const double w = std::min(len, v + step);
                        const double g = phi(w);
                        if ((g < 0.0) != in) {
                            // Bisect [v, w] for the sign change.
                            double lo = v, hi = w;
                            while (hi - lo > kCrossingTolerance * vs) {
                                const double mid = 0.5 * (lo + hi);
                                ((phi(mid) < 0.0) == in ? lo : hi) = mid;
                            }
                            const double x = 0.5 * (lo + hi);
                            if (in) detail::appendSegment(segs, start, x, len, axis, normalAt(start), normalAt(x));
                            else start = x;
                            in = !in;
                        }
                        v = w;
                        f = g;
                    }
                    if (in) detail::appendSegment(segs, start, len, len, axis, normalAt(start), {});
                }
            }
            detail::assignTileRow(fam, row);
        });
    }
    return stock;
}

}  // namespace dexelmill
