/// @file vdb_io.h
/// @brief Level sets to and from OpenVDB .vdb files (openvdb::io::File). This header does not
/// include OpenVDB.
#pragma once

#include <string>

#include "dexelmill/io/atomic_file.h"
#include "dexelmill/surface/levelset.h"

namespace dexelmill {

/// @brief Writes the level set's grid, with its metadata, to a .vdb file (through
/// writeFileAtomically; staged in `batch` when given): with the grids' offsets, as
/// openvdb::io::File writes, or without them where the target is written in place (a pipe cannot
/// go back to write them), as openvdb::io::Stream writes. Both read back.
/// @throw Error if the handle is null or the file cannot be written.
void writeVdb(const std::string& path, const LevelSet& levelSet, OutputBatch* batch = nullptr);

/// @brief Reads a float level-set grid from a .vdb file: the grid named `gridName`, or when that
/// is empty the grid named "stock" if there is one, else the first float grid of class level set
/// (or of unknown class). Every grid of the file is read (as openvdb::io::Stream reads), through a
/// stream that fails at the first read past the file's end, so that a file cut short is refused
/// there rather than parsed on from bytes never read.
/// @throw Error if the file is not a regular file, cannot be read, is not a complete OpenVDB file,
/// or holds no such grid.
LevelSet readVdb(const std::string& path, const std::string& gridName = "");

}  // namespace dexelmill
