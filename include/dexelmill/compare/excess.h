/// @file excess.h
/// @brief Excess after the cut: the material the stock still holds outside the design, how thick
/// it is (its distance to the design's surface), and where most of it is.
#pragma once

#include <cstddef>
#include <vector>

#include "dexelmill/compare/design.h"
#include "dexelmill/geometry/types.h"
#include "dexelmill/stock/tridexel.h"

namespace dexelmill {

/// @brief A connected region of excess thicker than the tolerance.
struct ExcessRegion {
    Box box;                ///< mm, to the cells of ExcessOptions::cell
    double volume = 0.0;    ///< mm^3 of material outside the design in those cells
    double thickness = 0.0; ///< mm, the largest distance from the design found in it
    Vec3 point{0.0};        ///< where that distance is
};

/// @brief What findExcess found.
struct Excess {
    /// mm^3 of stock outside the design, all of it (within the tolerance too), as the z family
    /// measures it (x's, else y's, without z dexels)
    double volume = 0.0;
    /// mm, the largest distance from the design of any stock the dexels hold (0 when none is
    /// farther than the tolerance), and where
    double thickness = 0.0;
    Vec3 point{0.0};
    /// Regions whose thickness exceeds the tolerance, most volume first
    std::vector<ExcessRegion> regions;
};

/// @brief Compares the cut stock with the design, both on one lattice.
///
/// Along every dexel kept by both, the stock's segments minus the design's are the excess. A piece
/// whose points all lie within `tolerance` of a design end along the dexel is within tolerance
/// (the distance to a surface is at most the distance along any line) and is not searched. The
/// others are grouped by the cells of a coarse grid they pass through, joined when the cells
/// touch; each group's thickness is found as in findGouges, within depthBound(tolerance, h) of its
/// largest, and groups at most `tolerance` thick are dropped. At most `maxRegions` are returned.
Excess findExcess(const DesignPart& design, const TriDexelStock& stock, double tolerance, std::size_t maxRegions = 10);

}  // namespace dexelmill
