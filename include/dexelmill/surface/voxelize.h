/// @file voxelize.h
/// @brief Stock from a solid given as a closed triangle mesh or as a level set: every dexel line
/// is cast against the solid, so a casting, a forging or the result of an earlier operation can
/// be the starting stock. This header does not include OpenVDB.
#pragma once

#include <cstddef>

#include "dexelmill/stock/tridexel.h"
#include "dexelmill/surface/levelset.h"
#include "dexelmill/surface/mesh.h"

namespace dexelmill {

/// @brief What casting a mesh into dexels met.
struct MeshCastStats {
    std::size_t hits = 0;  ///< ray-triangle crossings found
    /// Dexels whose crossings did not pair up (an open mesh, or rounding at a vertex); their
    /// segments then come from pairing the sorted crossings by parity, and a last unpaired
    /// crossing is dropped.
    std::size_t unpairedDexels = 0;
};

/// @brief A stock on `lattice` holding the solid bounded by a closed mesh.
///
/// For each dexel line the crossings with the triangles are found in the plane across the line
/// (2D edge functions, evaluated the same way for the two triangles of a shared edge, with a
/// top-left rule for points exactly on an edge or vertex, so a line through an edge or vertex
/// crosses once), sorted, and turned into segments by the non-zero winding rule: each crossing
/// counts +1 where the triangle faces against the line's direction, -1 where it faces along it.
/// Material outside the lattice's cell box is clipped.
MeshCastStats castMesh(const Mesh& mesh, TriDexelStock& stock);

/// @brief castMesh into a new stock on `lattice` keeping `families`.
TriDexelStock stockFromMesh(const Mesh& mesh, const Lattice& lattice,
                            FamilySet families = FamilySet::all(), MeshCastStats* stats = nullptr);

/// @brief A stock on `lattice` holding the solid where the level set is negative. Along each
/// dexel line the trilinearly interpolated value is marched (steps of 0.8 |phi|, at least a
/// quarter voxel and at most the narrow-band width) and every sign change is refined by
/// bisection to 1e-6 voxel.
/// @throw Error if the handle is null.
TriDexelStock stockFromLevelSet(const LevelSet& levelSet, const Lattice& lattice,
                                FamilySet families = FamilySet::all());

/// @brief The box holding the material of a level set: the centres of its negative voxels,
/// padded by one voxel (empty if none). A lattice for stockFromLevelSet.
Box materialBounds(const LevelSet& levelSet);

}  // namespace dexelmill
