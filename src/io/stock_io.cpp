#include "dexelmill/io/stock_io.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "dexelmill/error.h"
#include "dexelmill/io/file_name.h"
#include "dexelmill/io/mesh_io.h"
#include "dexelmill/io/vdb_io.h"
#include "dexelmill/surface/voxelize.h"

namespace dexelmill {

namespace {

/// How far the lattice box reaches past an STL's bounds, in units of h: the faces of a part
/// modelled at round coordinates then lie between lattice planes, not on them.
constexpr double kStlBoxMargin = 0.25;

/// Lattice spacings that differ by less than this fraction are the same spacing.
constexpr double kSameSpacing = 1e-9;

}  // namespace

Lattice stockLattice(const Mesh& mesh, double h) {
    // The padded box is no face of the solid: each dexel stands for its whole cell
    // (Lattice::share), the cells covering the solid. Only a box stock's faces are known exactly.
    Lattice lattice = Lattice::fromBox(mesh.bounds().padded(kStlBoxMargin * h), h);
    lattice.stockMax = lattice.cellBox().hi;
    return lattice;
}

Lattice stockLattice(const LevelSet& levelSet, double h) {
    const std::optional<Lattice> recorded = levelSet.lattice();
    if (recorded && std::abs(recorded->h - h) <= kSameSpacing * h) return *recorded;
    const Box box = materialBounds(levelSet);
    if (box.isEmpty()) throw Error("the level set holds no material (no negative voxel)");
    // The material's box, from voxels, is no exact face of the solid (see above).
    Lattice lattice = Lattice::fromBox(box, h);
    lattice.stockMax = lattice.cellBox().hi;
    return lattice;
}

TriDexelStock readStock(const std::string& path, double h, FamilySet families,
                        MeshCastStats* stats) {
    if (!(h > 0.0) || !std::isfinite(h))
        throw Error("stock from '" + path + "': spacing must be positive");
    const std::string ext = lowerExtension(path);
    if (ext == ".stl") {
        const Mesh mesh = readStl(path);
        return stockFromMesh(mesh, stockLattice(mesh, h), families, stats);
    }
    if (ext == ".vdb") {
        const LevelSet ls = readVdb(path);
        try {
            return stockFromLevelSet(ls, stockLattice(ls, h), families);
        } catch (const Error& e) {
            throw Error("'" + path + "': " + e.what());
        }
    }
    throw Error("stock from '" + path + "': unknown file type '" + ext + "' (expected .stl or .vdb)");
}

}  // namespace dexelmill
