/// @file grid_meta.h
/// @brief Names and helpers for the metadata dexelmill writes on its level-set grids.
#pragma once

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

}  // namespace dexelmill::detail
