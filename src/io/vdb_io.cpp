#include "dexelmill/io/vdb_io.h"

#include <openvdb/openvdb.h>

#include "dexelmill/error.h"
#include "dexelmill/io/atomic_file.h"
#include "dexelmill/surface/levelset_vdb.h"

namespace dexelmill {

namespace {

/// Writes grids as openvdb::io::File::write does (a random-access file: the grids' offsets in its
/// header), but to a stream of ours: File::write opens its own and never looks at its state, so a
/// full disk left a truncated file that was then renamed over the target.
class RandomAccessWriter : public openvdb::io::Archive {
public:
    void writeTo(std::ostream& out, const openvdb::GridCPtrVec& grids) const {
        Archive::write(out, grids, /*seekable=*/true);
    }
};

}  // namespace

void writeVdb(const std::string& path, const LevelSet& levelSet, OutputBatch* batch) {
    openvdb::FloatGrid::ConstPtr grid = gridOf(levelSet);
    if (!grid) throw Error("cannot write '" + path + "': the level set holds no grid");
    ensureOpenVdbInitialized();
    writeStreamAtomically(path, [&](std::ostream& out) {
        try {
            RandomAccessWriter().writeTo(out, openvdb::GridCPtrVec{grid});
        } catch (const openvdb::Exception& e) {
            throw Error("cannot write '" + path + "': " + e.what());
        }
    }, batch);
}

LevelSet readVdb(const std::string& path, const std::string& gridName) {
    ensureOpenVdbInitialized();
    try {
        openvdb::io::File file(path);
        file.open();
        openvdb::GridBase::Ptr base;
        if (!gridName.empty()) {
            if (!file.hasGrid(gridName))
                throw Error("'" + path + "' has no grid named '" + gridName + "'");
            base = file.readGrid(gridName);
        } else if (file.hasGrid("stock") &&
                   file.readGridMetadata("stock")->isType<openvdb::FloatGrid>()) {
            base = file.readGrid("stock");
        } else {
            openvdb::GridPtrVecPtr metas = file.readAllGridMetadata();
            for (const openvdb::GridBase::Ptr& m : *metas) {
                if (m->isType<openvdb::FloatGrid>() &&
                    (m->getGridClass() == openvdb::GRID_LEVEL_SET ||
                     m->getGridClass() == openvdb::GRID_UNKNOWN)) {
                    base = file.readGrid(m->getName());
                    break;
                }
            }
        }
        file.close();
        if (!base) throw Error("'" + path + "' holds no float level-set grid");
        openvdb::FloatGrid::Ptr grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
        if (!grid) throw Error("grid '" + base->getName() + "' in '" + path + "' is not a float grid");
        try {
            return levelSetFromGrid(grid);
        } catch (const Error& e) {
            throw Error("'" + path + "': " + e.what());
        }
    } catch (const openvdb::Exception& e) {
        throw Error("cannot read '" + path + "': " + e.what());
    }
}

}  // namespace dexelmill
