/// @file lattice.h
/// @brief The one lattice of the tri-dexel stock (method.md section 7). The stock owns this
/// convention; the level-set rebuild reads it from here and never recomputes it.
#pragma once

#include <array>

#include "dexelmill/geometry/types.h"

namespace dexelmill {

/// @brief A coordinate axis; also names a dexel family by its ray direction.
enum class Axis : int { X = 0, Y = 1, Z = 2 };

constexpr int index(Axis a) { return static_cast<int>(a); }
constexpr Axis axisFromIndex(int i) { return static_cast<Axis>(i); }
/// @brief 'x', 'y' or 'z'.
constexpr char axisName(Axis a) { return "xyz"[index(a)]; }
/// @brief The unit vector along an axis.
inline Vec3 axisVector(Axis a) {
    Vec3 v(0.0);
    v[index(a)] = 1.0;
    return v;
}

/// @brief Lattice points at origin + (i + 1/2) h per axis: the centres of the n cells of size h
/// that tile the stock box from its minimum corner. A dexel of family `a` runs along axis a
/// through the lattice points with fixed indices on the other two axes, so every cell edge lies
/// on exactly one dexel and faces at round heights fall between lattice lines.
struct Lattice {
    Vec3 origin{0.0};               ///< minimum corner of the stock box (mm)
    double h = 1.0;                 ///< spacing (mm)
    std::array<int, 3> n{1, 1, 1};  ///< lattice points per axis
    /// Maximum corner of the stock box (mm): no material lies beyond it. The last cells hang past
    /// it when a size is not a whole number of cells; share() clips them to it.
    Vec3 stockMax{1.0};

    /// @brief The lattice tiling `box` with spacing h: n = ceil(size / h) per axis (at least 1).
    /// @throw Error if the box is empty or degenerate, h is not positive, or the lattice would
    /// need more than 2^31 points along an axis.
    static Lattice fromBox(const Box& box, double h);

    /// @brief World coordinate of lattice index i along axis a.
    double coord(Axis a, int i) const { return origin[index(a)] + (i + 0.5) * h; }
    /// @brief World position of lattice point (i, j, k).
    Vec3 point(int i, int j, int k) const {
        return origin + (Vec3(i, j, k) + 0.5) * h;
    }
    /// @brief The width of the stock box's slab that lattice line i along axis a stands for, in
    /// cells: 1 inside, 0 for a line at or past the box's maximum face (it holds no material), and
    /// for the last line inside, the rest of the box up to that face (between 1/2 and 3/2 of a
    /// cell). The shares of a row sum to the box's size over h, so a dexel's material length times
    /// share(b) share(c) h^2 counts the stock box's volume exactly; inside, it is the midpoint
    /// rule, as before.
    double share(Axis a, int i) const;
    /// @brief share(b, ib) share(c, ic) for the dexel (ib, ic) of family `a`, b and c the two
    /// other axes in order (x: y, z; y: z, x; z: x, y), as DexelFamily's axisB and axisC.
    double dexelShare(Axis a, int ib, int ic) const {
        return share(axisFromIndex((index(a) + 1) % 3), ib) * share(axisFromIndex((index(a) + 2) % 3), ic);
    }
    /// @brief The box covered by the cells: origin to origin + n h.
    Box cellBox() const { return {origin, origin + Vec3(n[0], n[1], n[2]) * h}; }
    /// @brief Total number of lattice points.
    double pointCount() const { return double(n[0]) * n[1] * n[2]; }
    /// @brief Index range [first, last] of lattice coordinates along axis a inside [lo, hi];
    /// first > last when there is none.
    std::array<int, 2> indexRange(Axis a, double lo, double hi) const;
};

/// @brief How far a dexel end, stored as a float along the dexel from the lattice's origin, may lie
/// from the surface point it rounds (mm): half a float step at the lattice's longest side is 2^-24
/// of it; twice that covers the double arithmetic that found the point.
double endRounding(const Lattice& lattice);

}  // namespace dexelmill
