/// @file levelset_vdb.h
/// @brief The OpenVDB side of LevelSet, for the few translation units that need the grid itself
/// (io, tests, users with their own OpenVDB code). Including this pulls in openvdb/openvdb.h,
/// which compiles slowly: the rest of the library and the CLI use levelset.h only.
#pragma once

#include <openvdb/openvdb.h>

#include "dexelmill/surface/levelset.h"

namespace dexelmill {

/// @brief What a LevelSet handle holds.
struct LevelSet::Impl {
    openvdb::FloatGrid::Ptr grid;
};

/// @brief Calls openvdb::initialize() once per process (thread-safe). Every library entry point
/// that needs it calls this; users need not.
void ensureOpenVdbInitialized();

/// @brief The grid of a level set (null for a null handle). Do not modify it: copies of the
/// handle share it.
openvdb::FloatGrid::ConstPtr gridOf(const LevelSet& levelSet);

/// @brief Wraps a grid. It must be a level set: class GRID_LEVEL_SET (or unknown), a uniform
/// linear transform, and a positive background; a lattice it records must sit on its voxels, 0
/// to 7 from index 0 (detail::latticeOffset).
/// @throw Error otherwise.
LevelSet levelSetFromGrid(openvdb::FloatGrid::Ptr grid);

}  // namespace dexelmill
