/// @file stock_io.h
/// @brief Starting stock from a file: an STL (binary or ASCII) or a VDB level set, cast into
/// tri-dexels on a lattice that tiles the solid's bounding box.
#pragma once

#include <string>

#include "dexelmill/stock/tridexel.h"
#include "dexelmill/surface/levelset.h"
#include "dexelmill/surface/mesh.h"
#include "dexelmill/surface/voxelize.h"

namespace dexelmill {

/// @brief The lattice of spacing h a stock cast from `mesh` takes: its bounding box grown by h/4,
/// so that no face of a part modelled at round coordinates lies on a lattice line.
Lattice stockLattice(const Mesh& mesh, double h);

/// @brief The lattice of spacing h a stock taken from `levelSet` takes: the one the grid records
/// (dexelmill's own files) when h is its spacing, so that a stock written and read back keeps its
/// lattice; otherwise one tiling the material box (materialBounds).
/// @throw Error when the level set holds no material.
Lattice stockLattice(const LevelSet& levelSet, double h);

/// @brief Reads a solid from `path` and casts it into a stock of spacing h.
///
/// The format comes from the extension (.stl or .vdb, any case); the lattice is stockLattice's.
/// An STL must be closed (see stockFromMesh); a VDB's solid is where its level set is negative
/// (see stockFromLevelSet).
/// `stats`, if given, receives what casting an STL met (left as is for a VDB): unpaired dexels
/// mean the STL is not closed.
/// @throw Error for an unknown extension, an unreadable file, an empty solid, or h <= 0.
TriDexelStock readStock(const std::string& path, double h, FamilySet families = FamilySet::all(),
                        MeshCastStats* stats = nullptr);

}  // namespace dexelmill
