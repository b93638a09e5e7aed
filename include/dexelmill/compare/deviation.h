/// @file deviation.h
/// @brief How far a machined surface lies from the design: the signed distance to the design's
/// surface of every vertex of the machined mesh and of points inside its triangles, its statistics
/// and histogram, and the colours that show it (red where the machined surface lies inside the design, a gouge; blue where it lies
/// outside, excess; green within tolerance).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "dexelmill/compare/mesh_distance.h"
#include "dexelmill/geometry/types.h"
#include "dexelmill/io/picture.h"
#include "dexelmill/surface/mesh.h"

namespace dexelmill {

/// @brief The tolerances that say what is a gouge and what is excess (mm, 0 or more).
struct DeviationTolerance {
    double gouge = 0.01;   ///< deeper inside the design than this is a gouge
    double excess = 0.05;  ///< farther outside the design than this is excess
};

/// @brief One bin of the deviation histogram: the surface whose signed distance d lies between lo
/// and hi (mm). The bin within tolerance holds lo <= d <= hi; one of gouge holds lo <= d < hi, one
/// of excess lo < d <= hi.
struct DeviationBin {
    double lo = 0.0, hi = 0.0;
    double area = 0.0;           ///< mm^2
    std::size_t points = 0;      ///< the measured points (vertices and points inside triangles)
};

/// @brief A machined surface measured against the design.
struct Deviation {
    /// Per vertex of the machined mesh: the distance to the design's surface (mm), negative where
    /// the vertex lies inside the design; exact, except that a vertex within 1e-6 mm of the surface
    /// may be given a distance up to 1e-6 mm off, or the other sign, and that a distance within
    /// 1e-12 of the part's scale (its longest side or largest coordinate) is rounding, and 0.
    std::vector<double> distance;
    DeviationTolerance tolerance;
    /// The sampling's spacing (mm): every point of the machined surface lies within spacing /
    /// sqrt(3) of a measured point, and its distance to the design differs from that point's by
    /// at most as much. 0 for an empty mesh.
    double spacing = 0.0;
    double area = 0.0;                                    ///< the machined surface (mm^2)
    double gougeArea = 0.0, withinArea = 0.0, excessArea = 0.0;  ///< mm^2, by tolerance
    double rms = 0.0;                                     ///< area-weighted RMS distance (mm)
    double deepest = 0.0;   ///< the most negative distance measured (mm; 0 when no point is inside)
    double farthest = 0.0;  ///< the most positive distance measured (mm; 0 when no point is outside)
    Vec3 deepestPoint{0.0}, farthestPoint{0.0};
    /// Bins from the deepest to the farthest: gouge bins with edges at 1, 2, 5, 10, 20, ... times
    /// the gouge tolerance below zero, one bin within tolerance, excess bins at 1, 2, 5, 10, ...
    /// times the excess tolerance above zero (a tolerance below 1 um steps 1, 2, 5, ... um instead).
    /// An empty mesh has the bin within tolerance alone.
    std::vector<DeviationBin> histogram;
};

/// @brief Measures `machined` against the design (MeshDistance::signedDistance) at every vertex
/// and at points inside the triangles, so that a slot between a coarse mesh's vertices is not
/// missed: a triangle whose edges are longer than the sampling's spacing (Deviation::spacing) is
/// cut into k^2 smaller copies of itself whose corners are measured, or, where that takes fewer
/// points (a long thin triangle), measured along rows parallel to its longest edge. Each point
/// stands for the surface nearest it of its triangle (a third of the copies around it, or the
/// stretch of its row's strip whose foot on the row is nearest it), all within the spacing of it:
/// the areas are exact where the distance is the same over a point's share, and err only along the
/// lines where the class changes, by about the spacing. The spacing is the finest the point budget
/// allows (see deviation.cpp), whatever the tolerances: a mesh as fine as the simulate job's is
/// mostly measured at its vertices. Runs in parallel on the calling arena.
/// @throw Error for an empty design, a tolerance that is negative or not finite, or a vertex that
/// is not a finite point.
Deviation measureDeviation(const Mesh& machined, const MeshDistance& design, const DeviationTolerance& tolerance);

/// @brief The colour scale: green within tolerance; from light to dark red between the gouge
/// tolerance and `gougeFull` below zero, from light to dark blue between the excess tolerance and
/// `excessFull` above it; darkest beyond.
struct DeviationScale {
    DeviationTolerance tolerance;
    double gougeFull = 0.0, excessFull = 0.0;  ///< mm, positive
};

/// @brief A scale that spans the deviation measured: each side's full colour at its largest
/// distance, and at least at twice its tolerance.
DeviationScale deviationScale(const Deviation& deviation);

/// @brief The colour of a signed distance on the scale.
Rgb deviationColour(double distance, const DeviationScale& scale);

/// @brief The colour of every distance (Deviation::distance).
std::vector<Rgb> deviationColours(const std::vector<double>& distance, const DeviationScale& scale);

/// @brief The legend that explains the scale in a picture: the bar from dark red at the bottom
/// to dark blue at the top, in three equal parts (gouge, within tolerance, excess), labelled in mm.
PictureLegend deviationLegend(const DeviationScale& scale);

}  // namespace dexelmill
