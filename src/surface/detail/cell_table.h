/// @file cell_table.h
/// @brief The surface patches inside one lattice cell, from the signs at its eight corners: the
/// topology of marching cubes (Lorensen and Cline 1987) with face ambiguities resolved by a
/// per-face rule that both cells sharing the face see alike, so that the patches of neighbouring
/// cells meet edge to edge. A patch is a loop of edge crossings, oriented so that the fan from a
/// point inside the cell to each pair (x_i, x_i+1) faces out of the material (counter-clockwise
/// seen from outside). No OpenVDB here.
///
/// Numbering. Corner k sits at offset (k & 1, (k >> 1) & 1, (k >> 2) & 1). Edge 4 a + j runs along
/// axis a from the corner with offset 0 on a, offset j & 1 on axis (a + 1) % 3 and j >> 1 on axis
/// (a + 2) % 3. Face 2 a + s is the face across axis a at offset s.
#pragma once

#include <array>
#include <cstdint>

namespace dexelmill::detail {

constexpr int kCellCorners = 8;
constexpr int kCellEdges = 12;
constexpr int kCellFaces = 6;
/// A cell holds at most four patches (the corners of a tetrahedron inside, the rest outside).
constexpr int kMaxPatches = 4;

/// @brief The patches of one cell configuration.
struct CellPatches {
    std::uint8_t count = 0;                     ///< number of patches (loops)
    std::array<std::uint8_t, kMaxPatches> size{};   ///< crossings in each loop
    std::array<std::uint8_t, kCellEdges> edges{};   ///< the loops' edges, one after another
    /// The patch each crossing edge belongs to (0xff for edges without a crossing).
    std::array<std::uint8_t, kCellEdges> patchOf{};
};

/// @brief The corner at an edge's lower (end 0) or upper (end 1) end.
int edgeCorner(int edge, int end);
/// @brief The axis an edge runs along.
inline int edgeAxis(int edge) { return edge >> 2; }
/// @brief Offset (0 or 1) of corner k along axis a.
inline int cornerOffset(int corner, int axis) { return (corner >> axis) & 1; }

/// @brief The faces of a configuration (bit k of `inside` set when corner k is in material) on
/// which the corners alternate in, out, in, out: the ambiguous faces, as a bit mask over faces.
std::uint8_t ambiguousFaces(std::uint8_t inside);

/// @brief The patches of a configuration. Bit f of `joined` says, for an ambiguous face f, that
/// its two inside corners are joined across the face (the two segments then cut off its outside
/// corners); otherwise its inside corners are cut off. Bits of other faces are ignored.
const CellPatches& cellPatches(std::uint8_t inside, std::uint8_t joined);

/// @brief The asymptotic decider (Nielson and Hamann 1991) on one face: with the field bilinear
/// over the face and corner values f00, f10, f11, f01 in cyclic order, whether the saddle point
/// is in material (negative), which joins the inside corners.
bool insideJoinedAcrossFace(float f00, float f10, float f11, float f01);

/// @brief The corners of face f in cyclic order (the order insideJoinedAcrossFace expects).
std::array<int, 4> faceCorners(int face);

/// @brief Tables of a cell's edges: `face[i][j]`, the face holding both edges i and j (-1 where
/// none does, or i = j); `across[i][f]`, the index of edge i in the neighbour across face f (for
/// an edge on f, the same edge of the lattice).
struct EdgeTables {
    std::int8_t face[kCellEdges][kCellEdges];
    std::int8_t across[kCellEdges][kCellFaces];
    EdgeTables();
};
const EdgeTables& edgeTables();

/// @brief Where an edge of a cell starts (the offset of its lower corner) and the axis it runs along.
struct EdgeStart {
    int dx, dy, dz, axis;
};
const std::array<EdgeStart, kCellEdges>& edgeStarts();

}  // namespace dexelmill::detail
