/// @file tridexel.h
/// @brief The tri-dexel stock: up to three dexel families on one lattice.
#pragma once

#include <optional>
#include <string>

#include "dexelmill/stock/dexel.h"
#include "dexelmill/stock/lattice.h"

namespace dexelmill {

/// @brief Which dexel families a stock keeps, as a bit mask (bit i = axis i).
struct FamilySet {
    unsigned mask = 7;

    static FamilySet all() { return {7}; }
    static FamilySet only(Axis a) { return {1u << index(a)}; }
    /// @brief From text such as "xyz", "z" or "xz" (case-insensitive, any order).
    /// @throw Error on any other character, a repeat, or an empty set.
    static FamilySet parse(const std::string& text);
    bool has(Axis a) const { return (mask >> index(a)) & 1u; }
    int count() const { return int(has(Axis::X)) + int(has(Axis::Y)) + int(has(Axis::Z)); }
    /// @brief "xyz", "z", ...
    std::string str() const;
};

/// @brief Three orthogonal families of dexels on one lattice (method.md section 7).
///
/// Open/closed convention (method.md section 5): the swept tool is closed (a line lying in one of
/// its faces is cut along the face), so the material left is open: a segment [lo, hi] holds the
/// points strictly between its ends. A lattice point on a floor or wall that lies exactly on a
/// lattice plane is then empty for the dexel across the face (an end sits on it) and for the
/// dexels lying in the face (cut) alike.
class TriDexelStock {
public:
    /// @brief A stock with no material on `lattice`, keeping `families`.
    TriDexelStock(const Lattice& lattice, FamilySet families = FamilySet::all());

    /// @brief A solid box: the lattice tiles `box` with spacing h, and every dexel through the box's
    /// interior holds one segment spanning it (a line on one of its faces holds nothing).
    static TriDexelStock fromBox(const Box& box, double h, FamilySet families = FamilySet::all());

    const Lattice& lattice() const { return lattice_; }
    FamilySet families() const { return families_; }
    bool has(Axis a) const { return families_.has(a); }
    /// @throw Error if the family is not kept.
    DexelFamily& family(Axis a);
    const DexelFamily& family(Axis a) const;

    /// @brief The world line of dexel (ib, ic) of family a: origin at the lattice origin's
    /// coordinate on axis a, unit direction along a. Segment values are parameters on it.
    Line dexelLine(Axis a, int ib, int ic) const;

    /// @brief Material volume measured by one family: h^2 times its segment lengths (mm^3).
    double volume(Axis a) const;
    /// @brief The family volumes are reported by: z when kept, else x, else y.
    Axis measuringFamily() const { return has(Axis::Z) ? Axis::Z : (has(Axis::X) ? Axis::X : Axis::Y); }
    /// @brief Whether lattice point (i, j, k) is in material according to family a: strictly
    /// inside one of its dexel's segments.
    bool inside(Axis a, int i, int j, int k) const;
    /// @brief Heap bytes held by all families.
    std::size_t memoryBytes() const;
    /// @brief Number of dexels in the kept families.
    std::size_t dexelCount() const;
    /// @brief Segments in the kept families (each has two ends on the surface).
    std::size_t segmentCount() const;

private:
    Lattice lattice_;
    FamilySet families_;
    std::optional<DexelFamily> families3_[3];
};

}  // namespace dexelmill
