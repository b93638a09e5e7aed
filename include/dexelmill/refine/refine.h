/// @file refine.h
/// @brief The mesh brought closer to the exact part between the lattice's lines.
///
/// The dexel mesher puts its vertices on the lattice's crossings, which are exact, but between two
/// lattice lines a triangle is flat: a cusp left by passes closer together than the spacing, or the
/// rounded top of a wall, falls between them and is lost (README, Accuracy). Refinement asks the
/// sweep itself what lies there, on windows: short stretches of the coordinate axis nearest the
/// surface's normal, cut exactly as the stock's dexels are (the stock box minus every move's swept
/// tool, MoveSweep). The surface crossing found on a window is the exact part's.
///
///  1. The mesher's vertices are tested where they are. One placed on a sharp edge where its
///     crossings' planes meet may sit on a corner that a cusp the lattice did not see has cut
///     away: it moves onto the part, along the coordinate axis nearest its normal, or, where that
///     axis finds no crossing or the move would fold the mesh, along another axis (the shortest
///     move that does not fold, and only into the material: a vertex inside a wall thinner than
///     the lattice showed stays). Where every such move folds, the vertex goes half of its
///     shortest, or a quarter, or an eighth: nearer the part, not onto it. A vertex no axis finds
///     a crossing for is asked once more along the nearest, twice as far: a wedge's tip past the
///     next lattice line. (Vertices on crossings are exact and stay.)
///  2. Each edge is tested at its midpoint. One farther than a tolerance from the crossing there
///     is split at it, and its triangles with it (into two, three or four, the same way on both
///     sides of every edge, so the mesh stays closed). Later rounds test only the new edges.
///  3. Edges shorter than a sixteenth of a spacing are collapsed into their older end
///     (collapseShortEdges): a split next to a vertex leaves pieces too small for their normals to
///     mean anything. The vertices kept are on the part, and the surface moves by less than that.
///
/// A window along an axis nearly tangent to the part slides along it: at a wall's crease the
/// normal is the wall's and the top's together, and the crossing found may lie far along one of
/// them. So where the nearest axis's crossing lies farther than a tenth of the edge (of the
/// vertex's longest edge), the other axes within 75 degrees of the normal are asked too, and the
/// nearest crossing into the material is taken.
///
/// Error bound: every moved or new vertex (but those moved part of the way, which lie nearer the
/// part than they did) lies on the exact part's surface to the sweep's
/// accuracy (1e-6 mm; the windows are cut in double and kept as float offsets within half a
/// spacing, about 1e-8 mm), or, where a move whose tool axis turns makes the surface, to that
/// move's sweep tolerance (RefineOptions::turnTolerance). Between vertices the surface is still linear, so what remains is the
/// chord error of the finer edges, and features narrower than the edges the last round left.
///
/// Nothing folds: a split is not made where a piece would face away from the triangle it splits or
/// be a sliver; where the mesh then folds against its vertices' normals (checkMesh), the moves and
/// splits around the fold are undone. A window with no crossing of the right orientation (the
/// surface is farther than half a spacing: a crease the edge cuts across) changes nothing.
#pragma once

#include <cstddef>
#include <functional>

#include "dexelmill/geometry/types.h"
#include "dexelmill/path/toolpath.h"
#include "dexelmill/surface/mesh.h"
#include "dexelmill/sweep/turning.h"
#include "dexelmill/tool/tool.h"

namespace dexelmill {

/// @brief Options of refineMesh.
struct RefineOptions {
    /// Rounds of splitting; 0 leaves the mesh as it is (1 or more also snaps the vertices first).
    int rounds = 2;
    /// An edge is split where its midpoint is farther than this from the exact surface (mm).
    double tolerance = 1e-3;
    /// How far from the midpoint the crossing is looked for, each way along the axis (mm).
    double window = 0.5;
    /// Whether the shank's sweep removes material too (CutOptions::removeShankMaterial).
    bool removeShankMaterial = true;
    /// The tolerance of the sweeps of moves whose axis turns (CutOptions::turnTolerance): those
    /// moves are cut as the cutting loop cuts them, so a crossing they make lies within this of
    /// the exact part's surface rather than within the fixed-axis sweep's 1e-6 mm.
    double turnTolerance = kDefaultTurnTolerance;
    /// The most memory a round may add (bytes; 0: no limit). A round that would need more, by
    /// kRoundBytesPerTriangle, is not started: the mesh keeps the rounds done so far.
    double memoryBytes = 0.0;
    /// Called from the calling thread as the windows are cut: the stage ("snap 1" for the vertices
    /// along the axis nearest their normals, "snap 2" along the others, "refine 1", "refine 2", ...
    /// for the rounds' edges) and the share of its work done, as done / total. May be empty.
    std::function<void(const char* stage, std::size_t done, std::size_t total)> progress;
};

/// Working memory of a round per triangle of the mesh it starts from (bytes): the edge table, the
/// windows and their material, the pieces and the fold check. An upper figure: bear's first round
/// (with the snap) measured about 250.
constexpr double kRoundBytesPerTriangle = 400.0;

/// @brief What refineMesh did.
struct RefineStats {
    std::size_t queries = 0;      ///< vertices and edge midpoints tested (cut where a sweep comes near)
    std::size_t snapped = 0;      ///< mesher's vertices moved onto the exact part
    std::size_t snapRefused = 0;  ///< vertex moves undone because the mesh folded there
    /// Of the snapped, those moved only part of the way: every move onto the part folded.
    std::size_t snapPartial = 0;
    std::size_t split = 0;        ///< edges split (one new vertex each)
    std::size_t noCrossing = 0;   ///< midpoints with no crossing of the right side in the window
    /// Vertices and midpoints whose crossing along the axis nearest their normal lay far, moved or
    /// split at a nearer one along another axis.
    std::size_t laterAxis = 0;
    std::size_t refused = 0;      ///< splits given up: a piece would fold or be a sliver
    /// Triangles found passing through another, each time the snap's moves or a round's splits
    /// were tried; the moves there are undone and the splits refused, as a fold's are.
    std::size_t crossed = 0;
    std::size_t collapsed = 0;    ///< short edges collapsed after the rounds
    int rounds = 0;               ///< rounds made (fewer than asked when one split nothing)
    /// The memory the first round not started for lack of it would have needed (bytes), or 0.
    double roundNeeded = 0.0;
    MeshCheck check;              ///< checkMesh of the refined mesh
};

/// @brief Moves the vertices of `mesh` that lie off the exact part (`stock` minus the sweeps of
/// `path` with `tools`) onto it, then splits the edges whose midpoints lie off it at its surface,
/// round after round (see the file comment). Runs in the caller's task arena; the result does not
/// depend on the thread count.
/// @throw Error if a move uses a tool that is not in `tools`.
void refineMesh(Mesh& mesh, const Box& stock, const ToolPath& path, const ToolTable& tools,
                const RefineOptions& options = {}, RefineStats* stats = nullptr);

}  // namespace dexelmill
