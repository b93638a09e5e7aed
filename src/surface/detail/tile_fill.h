/// @file tile_fill.h
/// @brief Filling a dexel family a tile row at a time, for builders that compute every dexel's
/// segments from scratch (casting a mesh or a level set). Tiles are the unit of thread safety.
#pragma once

#include <vector>

#include "dexelmill/stock/dexel.h"

namespace dexelmill::detail {

/// @brief The segments of the dexels of one tile row: kTile rows of nb dexels each.
struct TileRowSegments {
    int tc = 0;
    int nb = 0;
    std::vector<std::vector<Segment>> dexels;  ///< index (ic - tc kTile) nb + ib

    TileRowSegments(int tileRow, int nbDexels)
        : tc(tileRow), nb(nbDexels), dexels(std::size_t(DexelTile::kTile) * nbDexels) {}
    std::vector<Segment>& at(int ib, int ic) {
        return dexels[std::size_t(ic - tc * DexelTile::kTile) * nb + ib];
    }
};

/// @brief Replaces every tile of row `row.tc` of `fam` with the row's segments.
inline void assignTileRow(DexelFamily& fam, TileRowSegments& row) {
    constexpr int kTile = DexelTile::kTile;
    std::uint16_t counts[DexelTile::kDexels];
    std::vector<Segment> segs;
    for (int tb = 0; tb < fam.tilesB(); ++tb) {
        segs.clear();
        for (int i = 0; i < DexelTile::kDexels; ++i) {
            const int ib = tb * kTile + i % kTile, ic = row.tc * kTile + i / kTile;
            counts[i] = 0;
            if (ib >= fam.nb() || ic >= fam.nc()) continue;
            const std::vector<Segment>& d = row.at(ib, ic);
            counts[i] = std::uint16_t(d.size());
            segs.insert(segs.end(), d.begin(), d.end());
        }
        fam.tile(tb, row.tc).assign(counts, segs.data());
    }
}

/// @brief Appends [lo, hi] (clipped to [0, len]) to sorted segments of a dexel along axis a, with
/// the material's outward normals nlo and nhi at its ends, merging a touching one. An end on or
/// clipped to the lattice's cell box takes the box face's normal.
inline void appendSegment(std::vector<Segment>& segs, double lo, double hi, double len, Axis a,
                          PackedNormal nlo, PackedNormal nhi) {
    if (lo <= 0.0) {
        lo = 0.0;
        nlo = PackedNormal::pack(-axisVector(a));
    }
    if (hi >= len) {
        hi = len;
        nhi = PackedNormal::pack(axisVector(a));
    }
    const float flo = float(lo), fhi = float(hi);
    if (!(fhi > flo)) return;
    if (!segs.empty() && segs.back().hi >= flo) {
        if (fhi > segs.back().hi) {
            segs.back().hi = fhi;
            segs.back().nhi = nhi;
        }
        return;
    }
    segs.push_back({flo, fhi, nlo, nhi});
}

}  // namespace dexelmill::detail
