/// @file design.h
/// @brief The design part, for comparing what the program cuts with it: its solid cast on the
/// stock's lattice, which the cutting loop watches (CutOptions::design), and its exact distance,
/// which measures how deep each move cut into it.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dexelmill/compare/mesh_distance.h"
#include "dexelmill/geometry/affine.h"
#include "dexelmill/geometry/types.h"
#include "dexelmill/path/toolpath.h"
#include "dexelmill/stock/cut.h"
#include "dexelmill/stock/tridexel.h"
#include "dexelmill/surface/voxelize.h"

namespace dexelmill {

/// @brief A distance to the design for queries in a few small regions (DesignPart::distanceNear):
/// an index of only the triangles there, or the design's whole index.
struct NearDistance {
    std::unique_ptr<MeshDistance> local;  ///< the index of the triangles near the regions, when built
    const MeshDistance* index = nullptr;  ///< what to ask: `local`, or the whole design's index
    const MeshDistance& operator*() const { return *index; }
};

/// @brief A design part ready for the comparison.
struct DesignPart {
    /// @brief The part whose solid on the lattice is `dexels`, measured through `distance` when
    /// given, else through an index of `mesh` built when first asked for (distance()).
    DesignPart(TriDexelStock dexels, Mesh mesh, std::unique_ptr<MeshDistance> distance, bool signs);
    DesignPart(DesignPart&&) noexcept;
    DesignPart& operator=(DesignPart&&) noexcept;
    ~DesignPart();

    std::string file;
    Box bounds;                   ///< the design mesh's bounding box (mm)
    TriDexelStock dexels;         ///< its solid on the stock's lattice
    MeshCastStats cast;           ///< what casting met: unpaired dexels mean an open mesh

    /// @brief The exact distance to the design's surface. Inside the design (where the dexels
    /// hold material) it is the depth. A part loaded for gouges and excess alone builds it on the
    /// first call: a cut that removes nothing deeper than the gouge tolerance along a dexel, and
    /// leaves nothing thicker than the excess tolerance, never pays for it. Safe to call from
    /// several threads and from inside TBB tasks: callers that arrive while it is being built
    /// join the build (tbb::collaborative_call_once).
    const MeshDistance& distance() const;
    /// @brief Hands the distance over (building it if needed), to measure the surface after the
    /// part's dexels are dropped. The part has no distance afterwards.
    std::unique_ptr<MeshDistance> takeDistance();
    /// @brief A distance exact for every point whose nearest point on the design lies inside one of
    /// the boxes `where`. That point lies on a triangle whose bounding box meets that box, so an
    /// index of those triangles alone answers exactly there; it is built when they are fewer than
    /// kNearShare of the design's. Otherwise, when a box is not finite, or when the whole index is
    /// already built, the answer is the whole index (distance()). A few gouges on a large design
    /// then cost a scan of its triangles rather than its whole index.
    NearDistance distanceNear(const std::vector<Box>& where) const;
    /// @brief The largest share of the design's triangles a local index (distanceNear) is built
    /// for: more, and the whole index, which later steps may reuse, costs little more.
    static constexpr double kNearShare = 0.25;

  private:
    struct Index;
    std::unique_ptr<Index> index_;
};

/// @brief Reads a design's mesh, a closed STL (binary or ASCII) or the zero surface of a VDB level
/// set (meshed by meshLevelSet at the grid's voxel size; distances are then to that mesh), and
/// places it with `place`. A map that mirrors (negative determinant) would turn the faces inside
/// out, so their order is reversed.
/// @throw Error naming the file for another format, an unreadable or empty file, or a map that
/// flattens the design (determinant 0).
Mesh readDesign(const std::string& path, const std::optional<Affine>& place = std::nullopt);

/// @brief Casts a design read by readDesign from `path` on `lattice`. `signs` says whether signed
/// distances will be asked for many points (a surface's deviation), which MeshDistance's `orient`
/// prepares for; gouge depths and excess thickness are unsigned. With `signs` the distance index
/// is surely needed and is built now, beside the cast; without, the part keeps the mesh and
/// builds the index only when asked (DesignPart::distance).
/// @throw Error naming the file when the design holds no material inside the lattice's box.
DesignPart loadDesign(Mesh mesh, const std::string& path, const Lattice& lattice,
                      FamilySet families = FamilySet::all(), bool signs = true);

/// @brief readDesign, then loadDesign.
DesignPart loadDesign(const std::string& path, const Lattice& lattice, FamilySet families = FamilySet::all());

/// @brief The stock a design implies when none is given: the design's bounding box, or, when the
/// program states a stock size (StatedStock) at least as large, a box of that size around it:
/// centred on the design in x and y; in z with its top at z = 0 (the CAM convention of the work
/// zero on the stock's top) when the design lies within that height below z = 0, else with its
/// bottom on the design's bottom. `note` receives a sentence saying which.
/// @throw Error when a stated side is smaller than the design's.
Box designStockBox(const Box& design, const std::optional<StatedStock>& stated, std::string& note);

/// @brief A move that removed material the design keeps, deeper than the tolerance.
struct Gouge {
    std::size_t move = 0;        ///< 0-based index into the path's moves
    double depth = 0.0;          ///< mm: the deepest point's distance inside the design's surface
    /// mm^3 of design material the move removed (MoveStats::designRemoved), as the z family
    /// measures it (x's, else y's, without z dexels)
    double volume = 0.0;
    Vec3 point{0.0};             ///< the deepest point found
};

/// @brief How far below the deepest point findGouges and findExcess may stop (mm): a quarter of
/// the tolerance or a hundredth of the spacing h, whichever is less, and at least 0.1 um.
double depthBound(double tolerance, double h);

/// @brief The gouges a cut made, in move order: for every move with design stretches
/// (CutResult::designStretches, from a cut with CutOptions::design = &design.dexels and
/// designDepth = tolerance), the deepest point of its stretches, kept if deeper than `tolerance`.
///
/// Depths are exact distances to the design's triangles (MeshDistance). Along a stretch the depth
/// changes by at most the distance moved, and the distance to one triangle is convex along a
/// line, so a branch and bound over pieces of the stretches finds a point within
/// depthBound(tolerance, h) of the deepest one. A stretch's ends are the floats the stock stores,
/// each within endRounding(lattice) of the end of the cut (5e-6 mm on a 40 mm stock), so a move is
/// kept when that point lies deeper than tolerance + endRounding. So every move that cuts deeper
/// than tolerance + depthBound + 2 endRounding along its dexels is reported, none that cuts at
/// most `tolerance` deep is, and the reported depth is that of a point of its stretches, within
/// endRounding of a real point of the cut.
std::vector<Gouge> findGouges(const DesignPart& design, const Lattice& lattice, const CutResult& cut, double tolerance);

}  // namespace dexelmill
