/// @file grid_meta.h
/// @brief Names and helpers for the metadata dexelmill writes on its level-set grids.
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include <openvdb/openvdb.h>

#include "dexelmill/error.h"
#include "dexelmill/stock/lattice.h"

namespace dexelmill::detail {

inline constexpr const char* kGridName = "stock";
inline constexpr const char* kMetaSpacing = "spacing";
inline constexpr const char* kMetaUnits = "units";
inline constexpr const char* kMetaSource = "source";
inline constexpr const char* kMetaLatticeOrigin = "lattice_origin";
inline constexpr const char* kMetaLatticeSize = "lattice_size";
inline constexpr const char* kMetaStockMax = "stock_max";

/// @brief Writes spacing, units ("mm"), source and the lattice onto a grid.
inline void writeMeta(openvdb::GridBase& grid, const Lattice& lattice, const std::string& source) {
    grid.insertMeta(kMetaSpacing, openvdb::DoubleMetadata(lattice.h));
    grid.insertMeta(kMetaUnits, openvdb::StringMetadata("mm"));
    grid.insertMeta(kMetaSource, openvdb::StringMetadata(source));
    grid.insertMeta(kMetaLatticeOrigin,
                    openvdb::Vec3DMetadata(
                        openvdb::Vec3d(lattice.origin.x, lattice.origin.y, lattice.origin.z)));
    grid.insertMeta(kMetaLatticeSize,
                    openvdb::Vec3IMetadata(openvdb::Vec3i(lattice.n[0], lattice.n[1], lattice.n[2])));
    grid.insertMeta(kMetaStockMax, openvdb::Vec3DMetadata(
                                       openvdb::Vec3d(lattice.stockMax.x, lattice.stockMax.y, lattice.stockMax.z)));
}

/// @brief The lattice recorded by writeMeta, if the grid has it.
inline std::optional<Lattice> latticeFromMeta(const openvdb::GridBase& grid) {
    const auto spacing = grid.getMetadata<openvdb::DoubleMetadata>(kMetaSpacing);
    const auto origin = grid.getMetadata<openvdb::Vec3DMetadata>(kMetaLatticeOrigin);
    const auto size = grid.getMetadata<openvdb::Vec3IMetadata>(kMetaLatticeSize);
    if (!spacing || !origin || !size) return std::nullopt;
    Lattice l;
    l.h = spacing->value();
    l.origin = Vec3(origin->value().x(), origin->value().y(), origin->value().z());
    l.n = {size->value().x(), size->value().y(), size->value().z()};
    if (!(l.h > 0.0) || l.n[0] < 1 || l.n[1] < 1 || l.n[2] < 1) return std::nullopt;
    // Files written before the stock box was recorded: the cells' box.
    const auto stockMax = grid.getMetadata<openvdb::Vec3DMetadata>(kMetaStockMax);
    l.stockMax = stockMax ? Vec3(stockMax->value().x(), stockMax->value().y(), stockMax->value().z())
                          : l.cellBox().hi;
    return l;
}

/// @brief The grid index of lattice point (0, 0, 0), per axis, for the lattice the grid records
/// (latticeFromMeta): the rebuild shifts the index space by 0 to 7 voxels (rebuildLevelSet),
/// which the transform holds. Zero for a grid that records no lattice.
/// @throw Error if the transform does not put that point on a voxel 0 to 7 from index 0.
inline std::array<int, 3> latticeOffset(const openvdb::GridBase& grid) {
    std::array<int, 3> offset{0, 0, 0};
    const std::optional<Lattice> lattice = latticeFromMeta(grid);
    if (!lattice) return offset;
    const openvdb::Vec3d zero = grid.transform().indexToWorld(openvdb::Vec3d(0.0));
    // The rebuild made the transform from this origin and h, so the offset is a whole number of
    // voxels up to the rounding of the sums below: a few DBL_EPSILON of their magnitudes, in
    // voxels; kWholeVoxels allows far more.
    constexpr double kWholeVoxels = 1e-6;
    for (int a = 0; a < 3; ++a) {
        const double h = lattice->h, origin = lattice->origin[a];
        const double voxels = (origin + 0.5 * h - zero[a]) / h;
        const double rounding = 16.0 * std::numeric_limits<double>::epsilon() * (std::abs(origin) + std::abs(zero[a]) + h) / h;
        const double whole = std::round(voxels);
        if (!(std::abs(voxels - whole) <= kWholeVoxels + rounding) || whole < 0.0 || whole > 7.0)
            throw Error("level set: grid '" + grid.getName() +
                        "' records a lattice its transform does not place on whole voxels 0 to 7 from index 0");
        offset[std::size_t(a)] = int(whole);
    }
    return offset;
}

}  // namespace dexelmill::detail
