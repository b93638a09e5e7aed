/// @file fine_features.h
/// @brief Material and cuts finer than the lattice: stretches of a dexel that hold no lattice
/// point, so that the level set, and every mesh, picture and file made from it, cannot show them.
///
/// The level set knows the part only at the lattice points (in material or not) and, between two
/// points of different kinds, where the surface crosses. A segment of material that holds no
/// lattice point (a wall thinner than the spacing that falls between two lattice planes, the tip
/// of a thin wedge, the top of a ridge between passes) has empty points at both ends: the mesh
/// takes that edge as empty and leaves the material out. A gap between two segments that holds
/// no lattice point (a slot or an engraved line narrower than the spacing) has points in
/// material at both ends, and the mesh fills it. The dexels themselves, and the volumes measured
/// on them, keep both exactly; a finer spacing shows them.
#pragma once

#include <cstddef>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/stock/tridexel.h"

namespace dexelmill {

/// @brief Stretches near one another: one thin wall, fin or slot, as far as the dexels show it.
struct FineRegion {
    /// Their volume as the family that sees the most of them measures it: h^2 times their lengths
    /// (mm^3). A feature thin along one axis is seen by that axis's family alone, so this is the
    /// best single estimate; what no family crosses is not in it.
    double volumeMm3 = 0.0;
    Box box;                ///< the stretches' extent, each as wide as its dexel's cell (mm)
    double widestMm = 0.0;  ///< the longest stretch (mm): the thickest part seen
    Vec3 widestAt{0.0};     ///< the middle of the longest stretch (mm)
    std::size_t stretches = 0;
};

/// @brief Stretches of one kind (material, or gaps between material) that no lattice point lies
/// in, over every kept family.
struct FineStretches {
    std::size_t count = 0;   ///< stretches, all families together
    double volumeMm3 = 0.0;  ///< over all regions (FineRegion::volumeMm3 per region, summed)
    double widestMm = 0.0;   ///< the longest stretch (mm)
    Vec3 widestAt{0.0};      ///< the middle of the longest stretch (mm)
    /// How many regions the stretches form: those within kFineRegionJoin lattice spacings of one
    /// another (by cells of that size that touch) are one region.
    std::size_t regionCount = 0;
    /// The regions with the most volume, most first, at most kFineRegionsKept.
    std::vector<FineRegion> regions;
};

/// Stretches whose middles lie in cells of this many spacings that touch (by a face, an edge or a
/// corner) are one region: a wall's stretches lie one spacing apart.
constexpr double kFineRegionJoin = 2.0;
/// Regions kept in FineStretches::regions.
constexpr std::size_t kFineRegionsKept = 10;

/// @brief One stretch of a dexel that holds no lattice point.
struct FineStretch {
    int family = 0;          ///< the dexel's axis (0 x, 1 y, 2 z)
    int ib = 0, ic = 0;      ///< the dexel in its family
    float lo = 0.0f, hi = 0.0f;  ///< its ends along the dexel (mm from the lattice origin)
};

/// @brief The stretches of `stock`'s kept families that no lattice point lies in (see the file
/// comment), material and gaps apart, in family, row and dexel order.
void findFineStretches(const TriDexelStock& stock, std::vector<FineStretch>& material,
                       std::vector<FineStretch>& gaps);

/// @brief What the lattice of a stock cannot show.
struct FineFeatures {
    /// Segments of material with no lattice point strictly inside: left out of the level set.
    FineStretches material;
    /// Gaps between two segments of one dexel with no lattice point in them, ends included: filled
    /// in the level set.
    FineStretches gaps;
};

/// @brief Finds the stretches of `stock`'s dexels that no lattice point lies in (see the file
/// comment), and groups them into regions. A lattice point is in material for a family exactly
/// as TriDexelStock::inside says.
FineFeatures finerThanLattice(const TriDexelStock& stock);

}  // namespace dexelmill
