/// @file grid_meta.h
/// @brief Names and helpers for the metadata dexelmill writes on its level-set grids.
#pragma once

#include <array>
#include <cmath>
#include <optional>
#include <string>

#include <openvdb/openvdb.h>

#include "dexelmill/stock/lattice.h"

namespace dexelmill::detail {

inline constexpr const char* kGridName = "stock";
inline constexpr const char* kMetaSpacing = "spacing";
inline constexpr const char* kMetaUnits = "units";
inline constexpr const char* kMetaSource = "source";
inline constexpr const char* kMetaLatticeOrigin = "lattice_origin";
inline constexpr const char* kMetaLatticeSize = "lattice_size";

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
    return l;
}

/// @brief The grid index of lattice point (0, 0, 0), per axis: the rebuild shifts the index space
/// by a whole number of voxels (rebuildLevelSet), which the transform records. Zero where the
/// transform's index origin is not a lattice point (a grid from elsewhere).
inline std::array<int, 3> latticeOffset(const openvdb::GridBase& grid, const Lattice& lattice) {
    const openvdb::Vec3d zero = grid.transform().indexToWorld(openvdb::Vec3d(0.0));
    // Lattice and transform come from the same h and origin: a whole number of voxels, to
    // rounding far below this.
    constexpr double kWholeVoxels = 1e-6;
    std::array<int, 3> offset{0, 0, 0};
    for (int a = 0; a < 3; ++a) {
        const double voxels = (lattice.origin[a] + 0.5 * lattice.h - zero[a]) / lattice.h;
        const double whole = std::round(voxels);
        if (std::abs(voxels - whole) < kWholeVoxels) offset[std::size_t(a)] = int(whole);
    }
    return offset;
}

}  // namespace dexelmill::detail
