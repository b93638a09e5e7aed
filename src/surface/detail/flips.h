/// @file flips.h
/// @brief The fan chords of the table path's feature patches that cross a crease, turned to run
/// along it (as in extended marching cubes), and turned back where fold repair cannot mend the
/// triangles a flip made. Pass 4 of contour.cpp, the only file that includes this header (it
/// includes OpenVDB, through contour_blocks.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "dexelmill/geometry/packed_normal.h"
#include "dexelmill/surface/mesh.h"
#include "surface/detail/cell_table.h"
#include "surface/detail/contour_blocks.h"

namespace dexelmill::detail {

/// @brief What the flip pass reads of the contourer after pass 3, and the mesh it flips in.
struct FlipInputs {
    /// The blocks, with where their crossings, patch vertices and triangles lie in the mesh.
    const BlockIndex* index = nullptr;
    /// The mesh: crossings below `patchVertexBase`, patch vertices from there on. The fans of the
    /// blocks' patches are rewritten in place.
    Mesh* mesh = nullptr;
    std::uint32_t patchVertexBase = 0;
    /// Per crossing: the material's outward normal, absent when unknown.
    const PackedNormal* crossingNormal = nullptr;
    /// Per patch vertex (mesh index - patchVertexBase): nonzero where it was placed on a crease or
    /// a corner (its crossings' planes have rank 2 or 3).
    const std::uint8_t* feature = nullptr;
    /// The loop of patch k of `patches`, those of the cell at p: its crossings' mesh indices into
    /// `out`, in order; returns their count. `near`: the blocks round the one holding p.
    /// @throw Error if no block holds one of the loop's crossings.
    std::function<int(const BlockIndex::Around& near, const Coord& p, const CellPatches& patches,
                      int k, std::uint32_t* out)>
        loop;
    /// The mixed cell at p: its patches and the mesh index of its first patch vertex; false for
    /// a plain cell, which has no patch vertex, and for a split cell, whose fans are never
    /// flipped.
    /// @throw Error if no block holds p.
    std::function<bool(const BlockIndex::Around& near, const Coord& p, const CellPatches*& patches,
                       std::uint32_t& firstPatch)>
        cell;
};

/// @brief Flips the fan chords of block b's feature patches that run across a crease: see the
/// definition. Writes only b's own triangles; returns the flips whose lower patch vertex is b's
/// (so that each is counted once).
std::size_t flipChords(const FlipInputs& in, const Block& b);

/// @brief Undoes the flips that made any of `triangles`, which fold repair could not mend: a flip
/// is judged with the vertices where pass 3 put them, and a later pull can turn one of its
/// triangles over. The pair (patch, xi, partner), (partner, xj, patch) goes back to the fan
/// triangles (patch, xi, xj), (partner, xj, xi); patch vertices are those from
/// `patchVertexBase` on. Returns the number of pairs undone.
std::size_t unflip(Mesh& mesh, std::uint32_t patchVertexBase,
                   const std::vector<std::uint32_t>& triangles);

}  // namespace dexelmill::detail
