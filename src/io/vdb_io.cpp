#include "dexelmill/io/vdb_io.h"

#include <openvdb/openvdb.h>

#include "dexelmill/error.h"
#include "dexelmill/io/atomic_file.h"
#include "dexelmill/surface/levelset_vdb.h"

namespace dexelmill {

void writeVdb(const std::string& path, const LevelSet& levelSet) {
    openvdb::FloatGrid::ConstPtr grid = gridOf(levelSet);
    if (!grid) throw Error("cannot write '" + path + "': the level set holds no grid");
    ensureOpenVdbInitialized();
    writeFileAtomically(path, [&](const std::string& temp) {
        try {
            openvdb::io::File file(temp);
            openvdb::GridCPtrVec grids{grid};
            file.write(grids);
            file.close();
        } catch (const openvdb::Exception& e) {
            throw Error("cannot write '" + path + "': " + e.what());
        }
    });
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
