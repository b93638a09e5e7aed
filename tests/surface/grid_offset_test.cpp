// The lattice a rebuilt grid records must sit on its voxels: a grid whose transform moved it off
// them, or too far, is refused when wrapped (as a .vdb read back would be), with a message.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "dexelmill/error.h"
#include "dexelmill/surface/levelset.h"
#include "dexelmill/surface/levelset_vdb.h"

using namespace dexelmill;

namespace {

/// A copy of the level set's grid moved by `voxels` along x, in world units of its voxel size.
openvdb::FloatGrid::Ptr movedCopy(const LevelSet& ls, double voxels) {
    openvdb::FloatGrid::Ptr grid = gridOf(ls)->deepCopy();
    grid->transform().postTranslate(openvdb::Vec3d(voxels * ls.voxelSize(), 0.0, 0.0));
    return grid;
}

}  // namespace

TEST_CASE("level set: a recorded lattice off the grid's voxels is refused", "[surface]") {
    const TriDexelStock stock = TriDexelStock::fromBox(Box{Vec3(-3.0, 2.0, 1.0), Vec3(9.0, 14.0, 7.0)}, 0.5);
    const LevelSet ls = rebuildLevelSet(stock);
    // The grid itself wraps, and its values are the lattice's whatever the offset.
    const LevelSet same = levelSetFromGrid(gridOf(ls)->deepCopy());
    CHECK(same.voxelValue(0, 5, 5) == ls.voxelValue(0, 5, 5));
    // Lattice point (0, 5, 5) lies 0.25 mm inside the low x face and 2.75 mm from the low y and z
    // faces: the axis-distance estimate of method.md section 7.
    CHECK(same.voxelValue(0, 5, 5) == Approx(-1.0 / std::sqrt(1.0 / (0.25 * 0.25) + 2.0 / (2.75 * 2.75))));
    // Moved by part of a voxel, or by nine: no offset 0 to 7 puts lattice point 0 on a voxel.
    for (double voxels : {0.3, -0.5, 9.0, -9.0}) {
        INFO("moved by " << voxels << " voxels");
        try {
            levelSetFromGrid(movedCopy(ls, voxels));
            FAIL("accepted");
        } catch (const Error& e) {
            CHECK(std::string(e.what()).find("whole voxels 0 to 7") != std::string::npos);
        }
    }
    // A grid that records no lattice is taken as it is.
    openvdb::FloatGrid::Ptr plain = movedCopy(ls, 0.3);
    plain->removeMeta("lattice_origin");
    CHECK_NOTHROW(levelSetFromGrid(plain));
}
