/// @file contour_blocks.h
/// @brief The contourer's work units: OpenVDB leaf blocks (8^3 lattice points) of the stock's
/// level set that hold surface, each with bit masks of its points' signs, its owned crossings and
/// its mixed cells, and the lookups from a lattice point to its block. Only contour.cpp and its
/// flip pass (flips.h) include this header (it includes OpenVDB).
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <openvdb/openvdb.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "dexelmill/surface/mesh.h"
#include "memory/pages.h"
#include "surface/detail/cell_table.h"

namespace dexelmill::detail {

using openvdb::Coord;

constexpr int kDim = 8;                      // OpenVDB leaf blocks are 8^3 lattice points
constexpr int kCells = kDim * kDim * kDim;   // cells (by lower corner) per block
static_assert(openvdb::FloatTree::LeafNodeType::DIM == kDim, "FloatTree leaves must be 8^3");

/// floor(i / 8) for negative i too.
inline int blockOf(int i) { return i >> 3; }

/// Local offset of a point in its block: x * 64 + y * 8 + z (OpenVDB's leaf order).
inline int localOffset(int x, int y, int z) { return ((x & 7) << 6) | ((y & 7) << 3) | (z & 7); }

/// Set bits of a word (a few shifts and adds, without the instruction older x86-64 CPUs lack).
inline int popcount(std::uint64_t x) {
    x = x - ((x >> 1) & 0x5555555555555555ull);
    x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
    x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
    return int((x * 0x0101010101010101ull) >> 56);
}

/// Bit z set when p[z] < 0, for the eight floats p[0 .. 7] (a leaf's row along z).
inline std::uint32_t negativeBits(const float* p) {
#if defined(__SSE2__)
    const __m128 zero = _mm_setzero_ps();
    return std::uint32_t(_mm_movemask_ps(_mm_cmplt_ps(_mm_loadu_ps(p), zero))) |
           std::uint32_t(_mm_movemask_ps(_mm_cmplt_ps(_mm_loadu_ps(p + 4), zero))) << 4;
#else
    std::uint32_t bits = 0;
    for (int z = 0; z < kDim; ++z) bits |= std::uint32_t(p[z] < 0.0f) << z;
    return bits;
#endif
}

/// Calls f(offset) for every set bit of words[0 .. n), in increasing offset order.
template <class F>
void forEachSetBit(const std::uint64_t* words, int n, F&& f) {
    for (int w = 0; w < n; ++w)
        for (std::uint64_t word = words[w]; word; word &= word - 1) f(w * 64 + __builtin_ctzll(word));
}

inline int popcountBelow(std::uint64_t word, int bit) {
    return popcount(word & ((std::uint64_t(1) << bit) - 1));
}

/// Per block: what it owns, and where its parts start in the mesh.
struct Block {
    Coord origin;
    /// Whether each of the block's points is in material (bit = local offset).
    std::uint64_t inside[8] = {};
    /// Owned crossings: bit (axis * 512 + offset) for the edge from the point at `offset` along
    /// the axis; and the crossings in the words before each word.
    std::uint64_t owned[24] = {};
    std::uint16_t ownedBefore[24] = {};
    /// Cells (by lower corner) with surface in them; the mixed cells in the words before each.
    std::uint64_t mixed[8] = {};
    std::uint16_t mixedBefore[8] = {};
    /// The mixed cells that are plain (Contourer::plainCell): a square of a face, two triangles
    /// and no patch vertex.
    std::uint64_t plain[8] = {};
    /// Per mixed cell in rank order: its corners in material (low byte) and its ambiguous faces
    /// whose inside corners are joined (high byte); kSplit for a split cell.
    std::vector<std::uint16_t> config;
    /// Patch vertices of the mixed cells before the n-th one, and in all (one more entry): one
    /// per patch, none in a plain cell.
    std::vector<std::uint16_t> patchBefore;
    std::uint32_t crossings = 0, patches = 0, triangles = 0;
    /// Of `triangles`, the table path's: the split cells whose lower corner the block holds come
    /// after them, and after its table path's patch vertices (patchBefore.back()) theirs.
    std::uint32_t tableTriangles = 0;
    std::uint32_t crossingBase = 0, patchBase = 0, triangleBase = 0;

    int rankOf(int off) const { return mixedBefore[off >> 6] + popcountBelow(mixed[off >> 6], off & 63); }
    bool isPlain(int off) const { return (plain[off >> 6] >> (off & 63)) & 1; }
    /// Whether the mixed cell of this rank is split (split_cells.h): the general path meshes it.
    /// Its configuration is kSplit, which no mixed cell has (no corner in material).
    bool isSplit(int rank) const { return config[std::size_t(rank)] == kSplit; }
    static constexpr std::uint16_t kSplit = 0xff00;
    const CellPatches& patchesOf(int rank) const {
        const std::uint16_t c = config[std::size_t(rank)];
        return detail::cellPatches(std::uint8_t(c & 0xff), std::uint8_t(c >> 8));
    }
    /// Calls f(offset, patches) for every mixed cell the table path meshes (split cells are the
    /// general path's), in increasing offset order.
    template <class F>
    void forEachTableCell(F&& f) const {
        int rank = 0;
        forEachSetBit(mixed, kCells / 64, [&](int off) {
            const int r = rank++;
            if (!isSplit(r)) f(off, patchesOf(r));
        });
    }
};

/// The blocks of a level set that hold surface, sorted by key, and the lookups into them.
class BlockIndex {
public:
    /// Finds the blocks of `grid` that hold surface (findBlocks, then keepSurfaceBlocks).
    void find(const openvdb::FloatGrid& grid) {
        findBlocks(grid);
        keepSurfaceBlocks(grid);
    }

    std::vector<Block, NoZeroAllocator<Block>> blocks;
    std::vector<std::uint64_t, NoZeroAllocator<std::uint64_t>> keys;

    static constexpr std::int64_t kKeyBias = std::int64_t(1) << 20;
    static std::uint64_t blockKey(const Coord& origin) {
        return (std::uint64_t(blockOf(origin.x()) + kKeyBias) << 42) | (std::uint64_t(blockOf(origin.y()) + kKeyBias) << 21) |
               std::uint64_t(blockOf(origin.z()) + kKeyBias);
    }
    static Coord blockOrigin(std::uint64_t key) {
        const int mask = (1 << 21) - 1;
        return Coord(kDim * (int((key >> 42) & mask) - int(kKeyBias)), kDim * (int((key >> 21) & mask) - int(kKeyBias)),
                     kDim * (int(key & mask) - int(kKeyBias)));
    }
    /// The block holding lattice point p, or null if the index has none. The lattice points the
    /// contourer asks about (the lower corner of a mixed cell, or of one of its edges with a
    /// crossing) have one when the level set changes sign only within its leaves or between a
    /// leaf and a tile: find() keeps every block with such a change. A sign change between two
    /// tiles, outside the band of distances, has none: the rebuild of a stock whose families
    /// disagree grossly makes those (its vote changes where no family has an end).
    const Block* blockAt(const Coord& p) const {
        const std::uint64_t key = blockKey(p);
        const auto it = std::lower_bound(keys.begin(), keys.end(), key);
        return it != keys.end() && *it == key ? &blocks[std::size_t(it - keys.begin())] : nullptr;
    }

    /// The blocks around one block (3 x 3 x 3, null where there is none), so that the lookups
    /// of its cells and their neighbours need no search.
    struct Around {
        Coord origin;
        const Block* near[27] = {};
        /// The block holding p (within one block of `origin`'s), or null as blockAt says.
        const Block* at(const Coord& p) const {
            const int i = (blockOf(p.x() - origin.x() + kDim) * 3 + blockOf(p.y() - origin.y() + kDim)) * 3 +
                          blockOf(p.z() - origin.z() + kDim);
            return near[i];
        }
    };

    Around around(const Block& b) const {
        Around a;
        a.origin = b.origin;
        for (int i = 0; i < 27; ++i) {
            const std::uint64_t key = blockKey(b.origin.offsetBy(kDim * (i / 9 - 1), kDim * (i / 3 % 3 - 1), kDim * (i % 3 - 1)));
            const auto it = std::lower_bound(keys.begin(), keys.end(), key);
            if (it != keys.end() && *it == key) a.near[i] = &blocks[std::size_t(it - keys.begin())];
        }
        return a;
    }

    /// Calls f(block) in parallel for every block.
    template <class F>
    void forEach(F&& f) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 8), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) f(i);
        });
    }

    /// rows[x][y]: bit z set when lattice point origin + (x, y, z) is in material; x, y, z in 0..8.
    using SignRows = std::uint16_t[kDim + 1][kDim + 1];

    static void readSigns(const openvdb::FloatGrid::ConstAccessor& acc, const Coord& origin, SignRows& rows) {
        for (auto& r : rows)
            for (auto& v : r) v = 0;
        for (int d = 0; d < 8; ++d) {
            const int dx = d & 1, dy = (d >> 1) & 1, dz = (d >> 2) & 1;
            const auto* leaf = acc.probeConstLeaf(origin.offsetBy(kDim * dx, kDim * dy, kDim * dz));
            const float tile = leaf ? 0.0f : acc.getValue(origin.offsetBy(kDim * dx, kDim * dy, kDim * dz));
            const float* data = leaf ? leaf->buffer().data() : nullptr;
            const int x0 = dx ? kDim : 0, x1 = dx ? kDim : kDim - 1;
            const int y0 = dy ? kDim : 0, y1 = dy ? kDim : kDim - 1;
            for (int x = x0; x <= x1; ++x)
                for (int y = y0; y <= y1; ++y) {
                    // The block's own row z = 0..7, or the next block's first point z = 8.
                    if (dz)
                        rows[x][y] |= std::uint16_t(((data ? data[localOffset(x, y, 0)] : tile) < 0.0f) << kDim);
                    else
                        rows[x][y] |= std::uint16_t(data ? negativeBits(data + localOffset(x, y, 0)) : tile < 0.0f ? 0xffu : 0u);
                }
        }
    }

    /// Bit z set when the cell at (x, y, z) of the block whose rows these are has corners both in
    /// and out of material; x, y in 0..7.
    static std::uint16_t mixedRow(const SignRows& rows, int x, int y) {
        const std::uint16_t r00 = rows[x][y], r10 = rows[x + 1][y], r01 = rows[x][y + 1], r11 = rows[x + 1][y + 1];
        const std::uint16_t both = r00 & r10 & r01 & r11, either = r00 | r10 | r01 | r11;
        return std::uint16_t(((either | (either >> 1)) & ~(both & (both >> 1))) & 0xff);
    }

    /// The lower corner of a mixed cell in a block that the index lacks, next to one it holds,
    /// if there is one: the level set changes sign between two tiles there (blockAt), and the mesh
    /// the index makes has a hole there. Reads the 26 blocks around each block held: a diagnosis
    /// for a mesh that came out open, not a step of every mesh.
    std::optional<Coord> mixedCellOutside(const openvdb::FloatGrid& grid) const {
        const auto acc = grid.getConstAccessor();
        SignRows rows;
        for (const Block& b : blocks)
            for (int i = 0; i < 27; ++i) {
                const Coord o = b.origin.offsetBy(kDim * (i / 9 - 1), kDim * (i / 3 % 3 - 1), kDim * (i % 3 - 1));
                if (blockAt(o)) continue;
                readSigns(acc, o, rows);
                for (int x = 0; x < kDim; ++x)
                    for (int y = 0; y < kDim; ++y)
                        if (const std::uint16_t mixed = mixedRow(rows, x, y)) return o.offsetBy(x, y, __builtin_ctz(mixed));
            }
        return std::nullopt;
    }

private:
    /// The blocks holding a cell's lower corner that may have surface: every grid leaf, and the
    /// blocks below one (a cell at a block's upper faces reaches into the next block). Cells with
    /// all corners in tiles have one sign: the flood fill puts leaves between inside and outside.
    void findBlocks(const openvdb::FloatGrid& grid) {
        // A bit per block position in the leaves' box, grown by one block downwards, read back
        // in the keys' order (x, then y, then z) instead of sorting eight keys per leaf. The box
        // lies within the lattice and its band: at most a bit per 512 lattice points.
        std::vector<Coord> origins;
        origins.reserve(grid.tree().leafCount());
        Coord lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
        for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
            origins.push_back(leaf->origin());
            lo.minComponent(leaf->origin());
            hi.maxComponent(leaf->origin());
        }
        decltype(keys) found;
        if (!origins.empty()) {
            lo.offset(-kDim);
            const std::int64_t nx = (hi.x() - lo.x()) / kDim + 1, ny = (hi.y() - lo.y()) / kDim + 1,
                               nz = (hi.z() - lo.z()) / kDim + 1;
            std::vector<std::uint64_t> bits(std::size_t((nx * ny * nz + 63) / 64), 0);
            for (const Coord& o : origins)
                for (int d = 0; d < 8; ++d) {
                    const Coord c = o.offsetBy(-kDim * (d & 1), -kDim * ((d >> 1) & 1), -kDim * ((d >> 2) & 1));
                    const std::int64_t b = ((c.x() - lo.x()) / kDim * ny + (c.y() - lo.y()) / kDim) * nz + (c.z() - lo.z()) / kDim;
                    bits[std::size_t(b / 64)] |= std::uint64_t(1) << (b % 64);
                }
            std::size_t marked = 0;
            for (std::uint64_t word : bits) marked += std::size_t(popcount(word));
            reservePopulated(found, marked);
            for (std::size_t w = 0; w < bits.size(); ++w)
                for (std::uint64_t word = bits[w]; word != 0; word &= word - 1) {
                    const std::int64_t b = std::int64_t(64 * w) + __builtin_ctzll(word);
                    found.push_back(blockKey(Coord(lo.x() + kDim * int(b / (ny * nz)), lo.y() + kDim * int(b / nz % ny),
                                                  lo.z() + kDim * int(b % nz))));
                }
        }
        keys = std::move(found);
    }

    /// Keeps the blocks whose points (with the next blocks' first points) are not all of one sign:
    /// those have a mixed cell, so a patch, and every lookup asks for one of those. Only they get a
    /// Block: on the hood at 1 mm more than half the candidates have none, and making and then
    /// dropping theirs had cost a tenth of the mesh's time.
    void keepSurfaceBlocks(const openvdb::FloatGrid& grid) {
        std::vector<std::uint8_t> keep(keys.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, keys.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
            const auto acc = grid.getConstAccessor();
            SignRows rows;
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                readSigns(acc, blockOrigin(keys[i]), rows);
                std::uint16_t any = 0, all = 0x1ff;
                for (const auto& row : rows)
                    for (std::uint16_t v : row) any |= v, all &= v;
                keep[i] = any != 0 && all != 0x1ff;
            }
        });
        std::size_t kept = 0;
        for (std::size_t i = 0; i < keys.size(); ++i)
            if (keep[i]) keys[kept++] = keys[i];
        keys.resize(kept);
        keys.shrink_to_fit();
        reservePopulated(blocks, kept);
        blocks.resize(kept);
        for (std::size_t i = 0; i < kept; ++i) blocks[i].origin = blockOrigin(keys[i]);
    }
};

}  // namespace dexelmill::detail
