/// @file contour.h
/// @brief The machined surface as a closed triangle mesh placed by the stock's Hermite data: the
/// exact dexel crossings and the normals kept with them. This header does not include OpenVDB.
#pragma once

#include <cstddef>

#include "dexelmill/stock/tridexel.h"
#include "dexelmill/surface/levelset.h"
#include "dexelmill/surface/mesh.h"

namespace dexelmill {

/// @brief Options of contourStock.
struct ContourOptions {
    /// Merging of flat regions, from 0 (every cell keeps its vertices) to 1 (triangles within 15
    /// degrees of each other merge, moving the surface by at most 0.05 h); in between both limits
    /// scale (mergeFlatRegions).
    double adaptivity = 0.0;
    /// Normals of one patch closer than this angle (radians) count as one smooth surface; a wider
    /// spread resolves a sharp edge (two planes) or corner (three) at the point that fits the
    /// crossings' tangent planes best.
    double featureAngle = 0.6;
};

/// @brief What contourStock did.
struct ContourStats {
    std::size_t cells = 0;           ///< lattice cells the surface crosses
    std::size_t patches = 0;         ///< surface patches with a vertex (one each)
    std::size_t plainCells = 0;      ///< cells crossed by one flat square: two triangles, no vertex
    std::size_t crossings = 0;       ///< edge crossings (one vertex each)
    std::size_t exactCrossings = 0;  ///< of which dexel endpoints (the rest: interpolated)
    std::size_t edgeVertices = 0;    ///< patch vertices placed on a sharp edge
    std::size_t cornerVertices = 0;  ///< patch vertices placed on a sharp corner
    std::size_t pulledBack = 0;      ///< patch vertices moved towards their loop to avoid a fold
    /// Patch vertices moved apart from another patch's of their cell, where the two fans crossed.
    std::size_t movedApart = 0;
    /// Pairs of a cell's patches whose fans cross but whose loops' hulls meet, so that no plane
    /// sets them apart: left crossing.
    std::size_t patchPairsLeftCrossing = 0;
    std::size_t flipped = 0;         ///< chords flipped to run along a crease
    std::size_t merged = 0;          ///< vertices merged away in flat regions (adaptivity)
    /// Lattice edges whose dexel has several ends between its two lattice points (a wall, fin or
    /// slot thinner than the spacing that no lattice point falls in); each end is a crossing.
    std::size_t splitEdges = 0;
    std::size_t splitCells = 0;    ///< cells round those edges, meshed by the general path
    std::size_t faceVertices = 0;  ///< vertices on cell faces that the general path added
    /// Runs of the contourer: one, and one more each time split cells' triangles folded and
    /// their edges were left to the table path: at most 5, the first four with split cells and the
    /// last without.
    int splitRuns = 1;
    /// Edges with several crossings left to the table path because their cells' triangles folded.
    std::size_t splitEdgesDropped = 0;
    MeshCheck check;                 ///< checkMesh of the mesh returned
};

/// @brief Contours the stock's level set with the stock's Hermite data.
///
/// The level set says which lattice cells the surface crosses (the signs at their corners); each
/// cell edge with a sign change lies on a dexel, whose endpoint there is the exact crossing, with
/// the material's normal. In each cell the crossings form loops, one per sheet of surface in the
/// cell (the patches of marching cubes, with the asymptotic decider on ambiguous faces, so that
/// neighbouring cells agree). Each patch gets one vertex inside its cell, where the tangent
/// planes at its crossings meet best (a quadric error function solved by a truncated SVD, as in
/// dual contouring, Ju et al. 2002), and is triangulated as a fan from that vertex to its
/// crossings (as in extended marching cubes, Kobbelt et al. 2001). A cell crossed by one flat
/// square across a lattice axis (the block's faces, a flat tool's floors and walls) takes the
/// square's two triangles instead, and no vertex. The mesh is closed and consistently oriented by
/// construction; its vertices on cell edges are the exact crossings.
///
/// A wall, fin or slot thinner than the spacing that no lattice point falls in has no sign change
/// in the level set, but its dexels cross it: an edge then holds several crossings. The cells
/// round such an edge are meshed by a general path (cell_loops.h) that joins the crossings on
/// each face by the cell table's rule where each edge has one, and by their tangents where an
/// edge has several, with a vertex on the face where a path's two ends lie on one edge. Stretches
/// thinner than 0.02 h, and those where the surface grazes the dexel, are left out; so are split
/// cells whose triangles fold after repair: the mesh is made again with their edges left to the
/// table path (up to four more times, the last without split cells).
///
/// Families that disagree a little (a near-tangent cut, a family marched from a VDB) only move
/// crossings: where a dexel disagrees with the level set's vote the crossing is interpolated. Where
/// they disagree grossly (a family empty where the others hold material, as a stock cast from an
/// open mesh has) the level set can change sign where no family has an end, outside its band,
/// and no closed mesh can be made: this throws instead of returning a mesh with a hole.
/// @throw Error if the level set holds no grid or was not rebuilt from this stock's lattice, or
/// if it changes sign outside its band next to the surface in it (the message gives the cell's
/// position in mm).
Mesh contourStock(const LevelSet& levelSet, const TriDexelStock& stock, const ContourOptions& options = {},
                  ContourStats* stats = nullptr);

}  // namespace dexelmill
