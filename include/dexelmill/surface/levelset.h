/// @file levelset.h
/// @brief The tri-dexel stock rebuilt as a narrow-band level set (method.md section 7), and its
/// mesh. This header does not include OpenVDB: LevelSet is an opaque handle. Code that needs the
/// openvdb::FloatGrid itself includes dexelmill/surface/levelset_vdb.h.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>

#include "dexelmill/geometry/types.h"
#include "dexelmill/stock/lattice.h"
#include "dexelmill/stock/tridexel.h"
#include "dexelmill/surface/mesh.h"

namespace dexelmill {

/// @brief A narrow-band signed-distance level set: an openvdb::FloatGrid of class level set,
/// negative inside material, world values in mm. Copies share the grid (it is not modified
/// after construction).
class LevelSet {
public:
    struct Impl;

    /// @brief An empty handle: no grid.
    LevelSet();
    ~LevelSet();
    LevelSet(const LevelSet&);
    LevelSet& operator=(const LevelSet&);
    LevelSet(LevelSet&&) noexcept;
    LevelSet& operator=(LevelSet&&) noexcept;

    /// @brief True when the handle holds no grid.
    bool isNull() const { return !impl_; }
    /// @brief Voxel size (mm): the lattice spacing h.
    double voxelSize() const;
    /// @brief Narrow-band half-width in voxels (background value / voxel size).
    double halfWidth() const;
    /// @brief Number of active (narrow-band) voxels.
    std::size_t activeVoxelCount() const;
    /// @brief Number of leaf nodes (8^3 voxel blocks).
    std::size_t leafCount() const;
    /// @brief Bytes held by the grid's tree (openvdb Tree::memUsage).
    std::size_t memoryBytes() const;
    /// @brief World box of the active voxels' centres (empty if none).
    Box activeBounds() const;
    /// @brief The grid's "source" metadata ("" if absent).
    std::string source() const;
    /// @brief The stock lattice recorded in the grid's metadata when it was rebuilt from a stock
    /// (or read from such a file); empty for grids from elsewhere.
    std::optional<Lattice> lattice() const;
    /// @brief The level-set value at a world point, trilinearly interpolated (mm).
    double valueAt(const Vec3& world) const;
    /// @brief The grid value at lattice point (i, j, k) (grid index (i, j, k) plus the rebuild's
    /// index offset; for a grid without a lattice, grid index (i, j, k)).
    float voxelValue(int i, int j, int k) const;

    /// @brief The shared implementation (holds the openvdb grid); see levelset_vdb.h.
    const std::shared_ptr<Impl>& impl() const { return impl_; }
    explicit LevelSet(std::shared_ptr<Impl> impl);

private:
    std::shared_ptr<Impl> impl_;
};

/// @brief Options of rebuildLevelSet.
struct RebuildOptions {
    /// Narrow-band half-width in voxels; at least 3 (OpenVDB's meshing and ray tracing need it).
    int halfWidth = 3;
    /// Families to use: the intersection with the stock's families. Inside/outside comes from a
    /// majority vote of the used families (a tie of two goes to z, else x); distances only from
    /// the used axes, a missing axis counting as an infinite distance.
    FamilySet families = FamilySet::all();
    /// Written to the grid's "source" metadata: what the stock came from.
    std::string source;
    /// The grid index of lattice point (0, 0, 0) per axis, each in 0..7; chosen by the rebuild
    /// when empty (see rebuildLevelSet). The values do not depend on it, only which 8^3 blocks
    /// hold them.
    std::optional<std::array<int, 3>> indexOffset;
};

/// @brief Rebuilds the stock as an OpenVDB narrow-band level set (method.md section 7).
///
/// The transform is scale h plus translation origin + (1/2 - o) h, so voxel (i,j,k) + o is lattice
/// point (i,j,k). The offset o (0..7 per axis) shifts the 8^3 leaves against the lattice: a flat
/// face across axis a, such as the stock box's, has a band six points deep along a, which two
/// leaves hold at one phase and a single leaf at another. The rebuild counts, over a sample of
/// the dexel ends along each axis, the blocks each end's band and its search reach would fill,
/// and takes the offset with the fewest (the box of the hood at 1 mm: about half the leaves).
/// A lattice point lies on one dexel per family; along each, the distance d_a to the
/// nearest dexel endpoint (an exact surface crossing) is known. The value is
///   phi = s / sqrt(dx^-2 + dy^-2 + dz^-2),   s = -1 in material, +1 outside,
/// exact for a locally planar surface. Points with |phi| < halfWidth h are active; all others
/// take +-halfWidth h (signed flood fill). Points outside the lattice lie on no dexel of the
/// families across them and are outside material. The grid is named "stock", class level set,
/// with metadata "spacing" (mm), "units" ("mm"), "source", and the lattice ("lattice_origin",
/// "lattice_size").
///
/// Memory: only the narrow-band leaves are allocated, straight into the tree; besides the grid
/// the rebuild holds a byte per 8^3 block of the padded lattice and a pointer per leaf.
/// @throw Error if halfWidth < 3 or no requested family is kept by the stock.
LevelSet rebuildLevelSet(const TriDexelStock& stock, const RebuildOptions& options = {});

/// @brief Options of meshLevelSet.
struct MeshOptions {
    /// openvdb::tools::volumeToMesh adaptivity in [0, 1]; 0 gives one vertex per surface cell.
    double adaptivity = 0.0;
};

/// @brief The zero isosurface as a closed triangle mesh: openvdb::tools::volumeToMesh, each quad
/// split along its shorter diagonal, triangles facing outward (counter-clockwise from outside).
/// @throw Error if adaptivity is outside [0, 1].
Mesh meshLevelSet(const LevelSet& levelSet, const MeshOptions& options = {});

}  // namespace dexelmill
