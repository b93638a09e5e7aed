/// @file stock_io.h
/// @brief Starting stock from a file: an STL (binary or ASCII) or a VDB level set, cast into
/// tri-dexels on a lattice that tiles the solid's bounding box.
#pragma once

#include <string>

#include "dexelmill/stock/tridexel.h"
#include "dexelmill/surface/voxelize.h"

namespace dexelmill {

/// @brief Reads a solid from `path` and casts it into a stock of spacing h.
///
/// The format comes from the extension (.stl or .vdb, any case). An STL must be closed; its
/// bounding box, grown by h/4 so no face lies on the box, is tiled by the lattice (see
/// stockFromMesh). A VDB's level set gives the material box of its negative voxels (see
/// stockFromLevelSet); when the grid records the lattice it was rebuilt from (dexelmill's own
/// files) and h equals its spacing, that lattice is used, so a stock written and read back keeps
/// its lattice.
/// `stats`, if given, receives what casting an STL met (left as is for a VDB): unpaired dexels
/// mean the STL is not closed.
/// @throw Error for an unknown extension, an unreadable file, an empty solid, or h <= 0.
TriDexelStock readStock(const std::string& path, double h, FamilySet families = FamilySet::all(),
                        MeshCastStats* stats = nullptr);

}  // namespace dexelmill
