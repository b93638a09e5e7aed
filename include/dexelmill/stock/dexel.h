/// @file dexel.h
/// @brief Dexels and dexel families: sorted lists of disjoint material segments along rays,
/// stored compactly in tiles.
///
/// Storage (docs/architecture.md): a family's dexels are grouped in tiles of kTile x kTile. A tile
/// keeps every segment of its dexels in one contiguous array, with an offset per dexel (its
/// capacity is the distance to the next offset) and a count. Endpoints are float, in mm along the
/// ray, relative to the lattice origin, each with the material's outward surface normal there
/// packed in 32 bits (PackedNormal: the Hermite data the mesher places the surface with). That is
/// 16 bytes a segment, so a one-segment dexel costs 22 bytes plus a share of the tile's fixed
/// overhead. Floats hold about 7 significant digits: 1e-4 mm at 1.7 m from the origin, well below
/// any practical lattice spacing. A tile with no material frees its arrays, so empty regions cost
/// only the tile header.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "dexelmill/geometry/packed_normal.h"
#include "dexelmill/span.h"
#include "dexelmill/stock/lattice.h"

namespace dexelmill {

/// @brief A material segment [lo, hi] along a dexel, mm relative to the lattice origin, with the
/// material's outward unit normal at each end (pointing against the dexel's axis at lo, along it
/// at hi, as a rule).
struct Segment {
    float lo = 0.0f;
    float hi = 0.0f;
    PackedNormal nlo;
    PackedNormal nhi;
};

/// @brief A read-only view of a dexel's segments.
using SegmentSpan = Span<Segment>;

/// @brief kTile x kTile dexels of one family with their segments in one array.
class DexelTile {
public:
    static constexpr int kTile = 16;
    static constexpr int kDexels = kTile * kTile;

    /// @brief Segments of dexel `local` (0 .. kDexels-1, index b + kTile * c within the tile).
    /// Inline: the rebuild and the mesher ask for millions of dexels.
    SegmentSpan segments(int local) const {
        if (offset_.empty()) return {};
        return {segs_.data() + offset_[std::size_t(local)], count_[std::size_t(local)]};
    }
    /// @brief Replaces the segments of a dexel. They must be sorted and disjoint.
    void setSegments(int local, const Segment* segs, std::size_t count);
    /// @brief Replaces the whole tile at once: `counts[i]` segments for dexel i (kDexels entries),
    /// all segments concatenated in dexel order. Sorted and disjoint per dexel.
    void assign(const std::uint16_t* counts, const Segment* segs);
    /// @brief Removes [lo, hi] from a dexel. Returns the length of material removed (mm).
    /// A segment end the cut makes at lo takes the normal `atLo`, one made at hi takes `atHi`: the
    /// outward normals of the material left there (the cutter's own, reversed). Ends that survive
    /// keep theirs.
    double subtract(int local, float lo, float hi, PackedNormal atLo = {}, PackedNormal atHi = {});
    /// @brief subtract with the new ends' normals unpacked (any length; a zero vector means none):
    /// they are packed only for the ends the cut actually makes.
    double subtract(int local, float lo, float hi, const Vec3& atLo, bool sharpLo, const Vec3& atHi, bool sharpHi);
    /// @brief True when no dexel holds material.
    bool empty() const { return offset_.empty(); }
    /// @brief Sum of segment lengths (mm).
    double materialLength() const;
    /// @brief Heap bytes held (capacity, not size).
    std::size_t memoryBytes() const;
    /// @brief Segments held by all dexels.
    std::size_t segmentCount() const;

private:
    void grow(int local, std::size_t needed);
    template <class NormalAt>
    double subtractImpl(int local, float lo, float hi, NormalAt&& normalAt);
    void releaseIfEmpty();

    // offset_[i] .. offset_[i + 1] is dexel i's capacity; count_[i] the segments in use.
    std::vector<std::uint32_t> offset_;
    std::vector<std::uint16_t> count_;
    std::vector<Segment> segs_;
};

/// @brief All dexels along one axis. Dexel (ib, ic) runs along `axis` through the lattice points
/// whose indices on the two other axes, taken cyclically (b = axis + 1, c = axis + 2, mod 3), are
/// ib and ic.
class DexelFamily {
public:
    static constexpr int kTile = DexelTile::kTile;

    DexelFamily(Axis axis, int nb, int nc);

    Axis axis() const { return axis_; }
    /// @brief The axis of the first and second dexel index.
    Axis axisB() const { return axisFromIndex((index(axis_) + 1) % 3); }
    Axis axisC() const { return axisFromIndex((index(axis_) + 2) % 3); }
    int nb() const { return nb_; }
    int nc() const { return nc_; }
    int tilesB() const { return tilesB_; }
    int tilesC() const { return tilesC_; }
    std::size_t tileCount() const { return tiles_.size(); }

    DexelTile& tile(int tb, int tc) { return tiles_[std::size_t(tb) + std::size_t(tilesB_) * tc]; }
    const DexelTile& tile(int tb, int tc) const {
        return tiles_[std::size_t(tb) + std::size_t(tilesB_) * tc];
    }
    /// Dexel (ib, ic)'s index within its tile. Indexes are never negative (0 <= ib < nb, 0 <= ic
    /// < nc), so unsigned arithmetic turns the division by kTile into a shift and a mask.
    static int localIndex(int ib, int ic) { return int(unsigned(ib) % kTile + kTile * (unsigned(ic) % kTile)); }
    /// The tile holding dexel (ib, ic).
    const DexelTile& tileOf(int ib, int ic) const { return tile(int(unsigned(ib) / kTile), int(unsigned(ic) / kTile)); }
    DexelTile& tileOf(int ib, int ic) { return tile(int(unsigned(ib) / kTile), int(unsigned(ic) / kTile)); }

    SegmentSpan segments(int ib, int ic) const { return tileOf(ib, ic).segments(localIndex(ib, ic)); }
    void setSegments(int ib, int ic, const Segment* segs, std::size_t count) {
        tileOf(ib, ic).setSegments(localIndex(ib, ic), segs, count);
    }
    double subtract(int ib, int ic, float lo, float hi, PackedNormal atLo = {}, PackedNormal atHi = {}) {
        return tileOf(ib, ic).subtract(localIndex(ib, ic), lo, hi, atLo, atHi);
    }
    /// @brief Sum of all segment lengths (mm).
    double materialLength() const;
    std::size_t memoryBytes() const;
    std::size_t segmentCount() const;

private:
    Axis axis_;
    int nb_, nc_, tilesB_, tilesC_;
    std::vector<DexelTile> tiles_;
};

}  // namespace dexelmill
