#include "dexelmill/stock/tridexel.h"

#include <cctype>
#include <cstdint>
#include <vector>

#include "dexelmill/error.h"

namespace dexelmill {

FamilySet FamilySet::parse(const std::string& text) {
    FamilySet s{0};
    for (char ch : text) {
        const char c = char(std::tolower(static_cast<unsigned char>(ch)));
        if (c < 'x' || c > 'z')
            throw Error("dexel families: '" + text + "' may only contain x, y and z");
        const unsigned bit = 1u << (c - 'x');
        if (s.mask & bit) throw Error("dexel families: '" + text + "' names " + c + " twice");
        s.mask |= bit;
    }
    if (s.mask == 0) throw Error("dexel families: at least one of x, y, z is needed");
    return s;
}

std::string FamilySet::str() const {
    std::string s;
    for (int a = 0; a < 3; ++a)
        if (has(axisFromIndex(a))) s += axisName(axisFromIndex(a));
    return s;
}

TriDexelStock::TriDexelStock(const Lattice& lattice, FamilySet families)
    : lattice_(lattice), families_(families) {
    for (int a = 0; a < 3; ++a) {
        if (!families.has(axisFromIndex(a))) continue;
        families3_[a].emplace(axisFromIndex(a), lattice.n[(a + 1) % 3], lattice.n[(a + 2) % 3]);
    }
}

TriDexelStock TriDexelStock::fromBox(const Box& box, double h, FamilySet families) {
    TriDexelStock stock(Lattice::fromBox(box, h), families);
    for (int a = 0; a < 3; ++a) {
        if (!families.has(axisFromIndex(a))) continue;
        DexelFamily& fam = *stock.families3_[a];
        // The box's faces across the family's axis, with their outward normals.
        const Segment full{0.0f, float(box.hi[a] - box.lo[a]), PackedNormal::pack(-axisVector(axisFromIndex(a))),
                           PackedNormal::pack(axisVector(axisFromIndex(a)))};
        std::vector<Segment> segs(DexelTile::kDexels, full);
        std::uint16_t counts[DexelTile::kDexels];
        for (int tc = 0; tc < fam.tilesC(); ++tc) {
            for (int tb = 0; tb < fam.tilesB(); ++tb) {
                // Tiles at the far edges hang over the lattice, and the last lattice line can lie
                // past the box (or on its face) when its size is not a whole number of cells:
                // those dexels miss the box's interior and stay empty.
                for (int i = 0; i < DexelTile::kDexels; ++i) {
                    const int ib = tb * DexelTile::kTile + i % DexelTile::kTile;
                    const int ic = tc * DexelTile::kTile + i / DexelTile::kTile;
                    const bool inBox = ib < fam.nb() && ic < fam.nc() &&
                                       stock.lattice_.coord(fam.axisB(), ib) < box.hi[index(fam.axisB())] &&
                                       stock.lattice_.coord(fam.axisC(), ic) < box.hi[index(fam.axisC())];
                    counts[i] = inBox ? 1 : 0;
                }
                fam.tile(tb, tc).assign(counts, segs.data());
            }
        }
    }
    return stock;
}

DexelFamily& TriDexelStock::family(Axis a) {
    if (!has(a)) throw Error(std::string("the stock keeps no ") + axisName(a) + " dexels");
    return *families3_[index(a)];
}

const DexelFamily& TriDexelStock::family(Axis a) const {
    if (!has(a)) throw Error(std::string("the stock keeps no ") + axisName(a) + " dexels");
    return *families3_[index(a)];
}

Line TriDexelStock::dexelLine(Axis a, int ib, int ic) const {
    const int ax = index(a), b = (ax + 1) % 3, c = (ax + 2) % 3;
    Line line;
    line.origin[ax] = lattice_.origin[ax];
    line.origin[b] = lattice_.coord(axisFromIndex(b), ib);
    line.origin[c] = lattice_.coord(axisFromIndex(c), ic);
    line.dir = axisVector(a);
    return line;
}

double TriDexelStock::volume(Axis a) const {
    // Each dexel's material times the share of the stock box's cross-section it stands for
    // (Lattice::share): 1 inside, clipped to the box at its maximum faces.
    const DexelFamily& fam = family(a);
    double sum = 0.0;
    for (int tc = 0; tc < fam.tilesC(); ++tc) {
        for (int tb = 0; tb < fam.tilesB(); ++tb) {
            const DexelTile& tile = fam.tile(tb, tc);
            if (tile.empty()) continue;
            for (int local = 0; local < DexelTile::kDexels; ++local) {
                const int ib = tb * DexelTile::kTile + local % DexelTile::kTile;
                const int ic = tc * DexelTile::kTile + local / DexelTile::kTile;
                if (ib >= fam.nb() || ic >= fam.nc()) continue;
                double length = 0.0;
                for (const Segment& g : tile.segments(local)) length += double(g.hi) - double(g.lo);
                if (length > 0.0) sum += length * lattice_.dexelShare(a, ib, ic);
            }
        }
    }
    return sum * lattice_.h * lattice_.h;
}

bool TriDexelStock::inside(Axis a, int i, int j, int k) const {
    const int ijk[3] = {i, j, k};
    const int ax = index(a);
    const DexelFamily& fam = family(a);
    const float v = float((ijk[ax] + 0.5) * lattice_.h);
    for (const Segment& s : fam.segments(ijk[(ax + 1) % 3], ijk[(ax + 2) % 3]))
        if (s.lo < v && v < s.hi) return true;
    return false;
}

std::size_t TriDexelStock::memoryBytes() const {
    std::size_t sum = 0;
    for (const auto& f : families3_)
        if (f) sum += f->memoryBytes();
    return sum;
}

std::size_t TriDexelStock::segmentCount() const {
    std::size_t sum = 0;
    for (const auto& f : families3_)
        if (f) sum += f->segmentCount();
    return sum;
}

std::size_t TriDexelStock::dexelCount() const {
    std::size_t sum = 0;
    for (const auto& f : families3_)
        if (f) sum += std::size_t(f->nb()) * std::size_t(f->nc());
    return sum;
}

}  // namespace dexelmill
