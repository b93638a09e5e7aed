/// @file cell_loops.h
/// @brief The surface patches inside one lattice cell whose edges may each hold any number of
/// crossings: the general form of cell_table.h, for cells around an edge whose dexel has several
/// ends between its two lattice points (a wall, fin or slot thinner than the spacing). No
/// OpenVDB here.
///
/// Each face is walked round its boundary, and its crossings split the boundary into arcs in
/// material and arcs out of it. The arcs in material that one region of material on the face
/// joins are found by the face rule (below); each region's boundary then runs along its arcs and,
/// between one arc's last crossing and the next arc's first, across the face. A path across the
/// face whose two ends lie on one edge (the face's slice of a thin wall's end, say) gets a face
/// vertex in between, so that no two triangles share that edge's chord from four sides. The face
/// vertex lies where the surface's slice through the face is expected, from the two ends'
/// normals: at their tangent lines' meeting point across a sharp edge (a wedge's tip; where the
/// normals are within the feature angle of opposite, a thin fin's sides, which run alike, on the
/// face rule's zero below that point's place along the edge), on the circular arc the normals
/// turn by on a smooth surface or where one end's sheet meets the face
/// at a grazing angle (its slice curls round too fast for its tangent), and otherwise on the face
/// rule's zero below the edge; at least a fifth of its chord into the face. The cell's paths, oriented as
/// cell_table.h orients its segments, chain into loops.
///
/// The face rule. A face with at most one crossing per edge follows the cell table: its
/// ambiguous case by the `joined` bit (the asymptotic decider on the level set's values). On a
/// face with several crossings on an edge the dexels say nothing about the inside of the face, so
/// the rule reads a field sampled on a grid of lines: the face's edges, a line between every two
/// crossings of parallel edges, and eight evenly spaced more. Inside the face the field is the
/// signed distance to the tangent line of the nearest crossing on an edge with several (a thin
/// wall or slot runs on along its sides), or, where that has no normal in the face, a
/// transfinite (Coons) blend of the four edges' signed distances to their nearest crossings. The
/// samples on the boundary are the edges' own membership, so every arc holds one. Material
/// samples that touch along a grid line are one region. A strip thinner than the grid's steps
/// that cuts a corner of the face slantwise falls between its samples, and its two ends read as
/// two regions; two regions whose paths across the face still cross when their lenses are at
/// their least depth are one. Then a region whose own paths still cross (a notch through a sheet
/// thinner than its lens's least depth, or round the corner where a crease's tangent lines meet,
/// which its path's chord cuts off) is split there in two. The rule reads only the face's edges,
/// so both cells sharing the face see the same regions.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "dexelmill/geometry/types.h"

namespace dexelmill::detail {

/// @brief The crossings on one cell edge, in increasing order along its axis.
struct EdgeCrossings {
    std::vector<std::uint32_t> ids;  ///< the caller's vertex ids
    std::vector<double> at;          ///< offsets from the edge's lower end, in (0, 1) spacings
    /// The material's outward unit normals there (zero where unknown), or none at all.
    std::vector<Vec3> normals;
};

/// @brief What one cell's loops are made from.
struct CellCrossings {
    std::uint8_t inside = 0;  ///< bit k: corner k (cell_table.h numbering) in material
    /// Per face: on a face with at most one crossing per edge and corners in, out, in, out, whether
    /// its inside corners are joined (cell_table.h's `joined`); other faces ignore it.
    std::uint8_t joined = 0;
    std::array<EdgeCrossings, 12> edges;  ///< per edge (cell_table.h numbering)
    /// Two crossings whose normals make a cosine below this bound a sharp edge (face vertices).
    double creaseCosine = 0.8253356149096783;  // cos(0.6 rad), ContourOptions::featureAngle
};

/// @brief Gives the id of the vertex on a face of the cell, at (u, v) in [0, 1]^2 of that face,
/// between crossings `from` and `to`, which lie on one edge. (u, v) run along axes (a + 1) % 3
/// and (a + 2) % 3 of the face across axis a, from its lowest corner. Both cells sharing the face
/// ask for it with the same (from, to) pair, in either order, and the same point.
using FaceVertexFn = std::function<std::uint32_t(int face, std::uint32_t from, std::uint32_t to, double u, double v)>;

/// @brief The cell's loops: ids in order, each oriented as cell_table.h orients its loops (the fan
/// from a point inside the cell faces out of the material). Every crossing lies on exactly one
/// loop, once; face vertices come from `faceVertex`.
/// @pre the crossings on each edge agree with its corners: their number is odd exactly where the
/// two corners differ.
std::vector<std::vector<std::uint32_t>> cellLoops(const CellCrossings& cell, const FaceVertexFn& faceVertex);

}  // namespace dexelmill::detail
