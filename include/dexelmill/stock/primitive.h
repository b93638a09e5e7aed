/// @file primitive.h
/// @brief Round starting stocks: a cylinder (bar stock, the usual start of 4-axis work) or a cone
/// frustum (a part turned on a lathe before milling), cast into tri-dexels exactly.
#pragma once

#include "dexelmill/stock/tridexel.h"

namespace dexelmill {

/// @brief A solid frustum of a right circular cone: the points p with 0 < t < height, where
/// t = (p - base) . axis, lying less than r(t) = r0 + (r1 - r0) t / height from the axis line.
/// r0 == r1 is a cylinder; either radius may be 0 (a cone with its apex on a face).
struct Frustum {
    Vec3 base{0.0};          ///< centre of the face at t = 0 (mm)
    Vec3 axis{0, 0, 1};      ///< unit direction from the base face to the top face
    double height = 1.0;     ///< distance between the faces (mm)
    double r0 = 1.0;         ///< radius at the base face (mm)
    double r1 = 1.0;         ///< radius at the top face (mm)

    /// @throw Error unless the axis is a non-zero finite vector (it is normalised), the height is
    /// positive, both radii are at least 0 and one is positive.
    static Frustum make(const Vec3& base, const Vec3& axis, double height, double r0, double r1);

    /// @brief The smallest box holding the solid: per axis the two end discs' extents,
    /// r sqrt(1 - axis_i^2) about their centres.
    Box bounds() const;
    /// @brief Exact volume, pi h (r0^2 + r0 r1 + r1^2) / 3 (mm^3).
    double volume() const;
};

/// @brief Where a line p(s) = origin + s dir (dir a unit vector) runs inside a frustum: the open
/// interval (lo, hi) of s, with the solid's outward unit normals at both ends. `empty` when the
/// line misses the interior or only touches the surface.
struct FrustumChord {
    bool empty = true;
    double lo = 0.0, hi = 0.0;
    Vec3 nlo{0.0}, nhi{0.0};
    /// An end on the rim where a face meets the side: the solid has no single normal there.
    bool sharpLo = false, sharpHi = false;
};

/// @brief The chord of a line through a frustum, in closed form: the slab of the two faces
/// intersected with the quadric of the side (a frustum is convex, so one interval). Exact up to
/// rounding: the roots come from the numerically stable form of the quadratic formula.
FrustumChord frustumChord(const Frustum& f, const Vec3& origin, const Vec3& dir);

/// @brief A stock holding the frustum on `lattice` (Lattice::fromBox(f.bounds(), h) tiles it):
/// every dexel holds the chord of its line as one segment (or nothing), with the side's or the
/// face's outward normal at each end.
TriDexelStock stockFromFrustum(const Frustum& f, const Lattice& lattice, FamilySet families = FamilySet::all());

}  // namespace dexelmill
