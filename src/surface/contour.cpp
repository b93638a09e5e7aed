// Contouring a stock's level set with its Hermite data (contour.h).
//
// First the split cells are found (detail/split_cells.h): those round a lattice edge whose dexel
// has several ends between its two points, a wall or slot thinner than the spacing. They are
// meshed apart, one after another (they are few), and the passes below skip them.
//
// The work is split by OpenVDB leaf blocks (8^3 lattice points, detail/contour_blocks.h) whose
// points, with the next blocks' first ones, are not all of one sign (their cells hold surface), in
// passes that each run in parallel over the blocks and write to disjoint places, so the mesh is the
// same for any thread count:
//  1. count: per block, from the signs of the grid's values (read bit-parallel, a row of 9 bits
//     along z at a time), the crossings on the edges its points own (the edge from a point along
//     +x, +y or +z), and the configuration of every cell whose lower corner it holds and that the
//     surface crosses (a mixed cell), with its patches and triangles, and whether it is plain (one
//     flat square across an axis, read from the dexels: two triangles, no patch vertex);
//  2. crossings: each owned crossing's position goes to the mesh, its normal to a side array;
//  3. patches: each patch's vertex from its crossings (quadric error function,
//     detail/patch_vertex.h), and its fan, the vertices of a cell's patches whose fans cross moved
//     apart (detail/patches_apart.h); a plain cell's square;
//  4. flips: the fan chords of feature patches that cross a crease are turned to run along it
//     (detail/flips.h);
// the split cells' vertices and fans come between passes 3 and 4. Then the mesh is checked, and
// the vertices of folded triangles are pulled back towards their loops (repairAndCheckMesh), and
// flips whose triangles still fold are undone (detail::unflip) before a second repair; split
// cells whose triangles still fold are left to the table path in a new run (contourStock). With
// adaptivity flat regions are merged (mergeFlatRegions).
// Passes 2 to 4 read only what pass 1 stored per block: bit masks with prefix counts, which turn a
// lattice point or cell into a mesh index, and the mixed cells' configurations.
// The blocks hold every cell with surface unless the level set changes sign between two of its
// tiles, outside its band (families that disagree grossly make that): then a lookup finds no block,
// or the mesh comes out open next to such a cell, and the contourer throws Error naming the cell
// (throwOutsideBand) instead of reading a block that is not there or returning a mesh with a hole.
#include "dexelmill/surface/contour.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <vector>

#include <openvdb/openvdb.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "dexelmill/error.h"
#include "dexelmill/geometry/packed_normal.h"
#include "dexelmill/surface/levelset_vdb.h"
#include "dexelmill/surface/simplify.h"
#include "memory/pages.h"
#include "surface/detail/cell_table.h"
#include "surface/detail/contour_blocks.h"
#include "surface/detail/flips.h"
#include "surface/detail/grid_meta.h"
#include "surface/detail/patch_vertex.h"
#include "surface/detail/patches_apart.h"
#include "surface/detail/split_cells.h"

namespace dexelmill {

namespace {

using detail::Block;
using detail::CellPatches;
using detail::EdgeStart;
using detail::edgeStarts;
using detail::forEachSetBit;
using detail::kCells;
using detail::kDim;
using detail::localOffset;
using detail::popcount;
using detail::popcountBelow;
using openvdb::Coord;


/// A crossing is kept at least this fraction of h away from the lattice points at its edge's
/// ends, so that crossings on different edges never coincide (a surface through a lattice point
/// crosses all its edges there) and stay distinct after rounding to float in a mesh file. It moves
/// a crossing by at most this much.
constexpr double kCornerGap = 1e-3;

/// A triangle whose normal makes a cosine below this with the sum of its vertices' normals is
/// treated as folded and repaired: rounding vertices to float, as mesh files do (relative 6e-8,
/// so 1e-4 mm at 1.7 m), turns a triangle a lattice cell across (1 mm at that size) by 1e-4 rad
/// at most, a tenth of this margin.
constexpr double kFoldMargin = 1e-3;

/// How far from a loop's mass point towards a crossing, or the midpoint of two, the last resort of
/// fold repair tries its candidate positions.
constexpr double kCandidateReach[] = {0.5, 0.9};

/// Rounds of fold repair; after the last a patch vertex that still folds sits on its mass point.
constexpr int kPullRounds = 8;

/// Runs of the contourer that leave the split cells with folds to the table path, before a last
/// run without split cells. An edge left to the table path changes the cells round it, and those
/// may fold in turn: boat-xyzac.ngc at h = 0.25 mm, its split regions opened round crease corners
/// (cell_loops.cpp), left 199 edges (3 round cells whose fans crossed, crossingPatchTriangles),
/// then 3 and 3 more, and none at the fourth run; after three the whole boat lost its 13,487
/// edges with several crossings to the last run.
constexpr int kSplitRetries = 3;

/// Patches of one cell whose triangles pass through each other by more than this (in h): split
/// ones are left to the table path as folds are (detail::crossingPatchTriangles), the table path's
/// have their vertices moved apart (detail::keepPatchesApart). Far below the dexel ends' float
/// precision, far above the rounding of the vertices' doubles.
constexpr double kFanCrossing = 1e-9;

/// How far towards the middle of its lens's chord the last resort of fold repair tries a split
/// cell's face vertex (split_cells.h).
constexpr double kFaceVertexReach[] = {0.25, 0.5, 0.75};

/// Adaptivity 1 merges flat regions whose normals stay within this angle (15 degrees) and whose
/// vertices stay within this fraction of h of the merged surface; smaller adaptivities scale both.
constexpr double kMergeAngle = 0.2617993877991494;
constexpr double kMergeDistance = 0.05;

/// A surface crossing on a lattice edge.
struct Crossing {
    Vec3 p{0.0};
    PackedNormal n;  ///< the material's outward normal; absent when unknown
    bool exact = false;
};

class Contourer {
public:
    Contourer(const openvdb::FloatGrid& grid, const TriDexelStock& stock, const ContourOptions& options,
              std::vector<std::pair<detail::GridPoint, int>> excluded, bool noSplit)
        : grid_(grid), stock_(stock), lattice_(stock.lattice()), h_(lattice_.h), featureAngle_(options.featureAngle),
          vertexRule_(h_, options.featureAngle), excluded_(std::move(excluded)), noSplit_(noSplit) {
        // From the lattice the grid records (contourStock checked it is the stock's).
        const std::array<int, 3> off = detail::latticeOffset(grid);
        offset_ = Coord(off[0], off[1], off[2]);
        if (!(options.adaptivity >= 0.0 && options.adaptivity <= 1.0))
            throw Error("contouring: adaptivity must lie in [0, 1], got " + std::to_string(options.adaptivity));
        adaptivity_ = options.adaptivity;
        for (int a = 0; a < 3; ++a)
            for (int side = 0; side < 2; ++side)
                for (int k = 0; k < 4; ++k) {
                    Vec3 n(0.0);
                    n[(a + 1) % 3] = (k & 1) ? -0.0 : 0.0;
                    n[(a + 2) % 3] = (k & 2) ? -0.0 : 0.0;
                    n[a] = side ? -1.0 : 1.0;
                    axisNormal_[std::size_t(2 * a + side)][std::size_t(k)] = PackedNormal::pack(n).bits;
                }
    }

    /// The edges with several crossings round split cells whose triangles still folded after
    /// repair, in the last run: contourStock runs again with them left to the table path.
    const std::vector<std::pair<detail::GridPoint, int>>& foldedSplitEdges() const { return foldedSplitEdges_; }

    Mesh run(ContourStats& stats) {
        index_.find(grid_);
        findSplit();
        countPass();
        unplacedPatches_ = unplacedTriangles_ = 0;
        for (std::size_t c = 0; c < split_.cells.size(); ++c) {
            if (splitPlaced_[c]) continue;
            const std::uint32_t p0 = split_.cellPatchStart[c], p1 = split_.cellPatchStart[c + 1];
            unplacedPatches_ += p1 - p0;
            unplacedTriangles_ += split_.loopStart[p1] - split_.loopStart[p0];
        }
        // Prefix sums: crossings first, then the split cells' vertices, then patch vertices in
        // block order, each block's split cells' after its own; the split cells of blocks with no
        // surface of their own last. Their triangles the same way: kept with their blocks, the
        // mesh's vertices and triangles stay in step, so that checking it builds its vertex
        // stars piece by piece (StarChunks).
        std::uint64_t crossings = 0, patches = 0, triangles = 0, cells = 0, plainCells = 0;
        for (Block& b : index_.blocks) {
            b.crossingBase = std::uint32_t(crossings);
            crossings += b.crossings;
        }
        const std::uint64_t splitPoints = split_.points.size();
        for (Block& b : index_.blocks) {
            b.patchBase = std::uint32_t(crossings + splitPoints + patches);
            patches += b.patches;
            b.triangleBase = std::uint32_t(triangles);
            triangles += b.triangles;
            cells += b.config.size();
            for (std::uint64_t w : b.plain) plainCells += std::uint64_t(popcount(w));
        }
        const std::uint64_t vertices = crossings + splitPoints + patches + unplacedPatches_;
        placeSplitPatches(crossings + splitPoints + patches, triangles);
        triangles += unplacedTriangles_;
        if (vertices > std::numeric_limits<std::uint32_t>::max() || triangles > std::numeric_limits<std::uint32_t>::max())
            throw Error("contouring: the mesh would have more than 2^32 vertices or triangles; use a larger spacing");
        detail::reservePopulated(mesh_.vertices, vertices);
        detail::reservePopulated(mesh_.triangles, triangles);
        detail::reservePopulated(crossingNormal_, crossings + splitPoints);
        mesh_.vertices.resize(vertices);
        mesh_.triangles.resize(triangles);
        crossingNormal_.resize(crossings + splitPoints);
        feature_.assign(patches + unplacedPatches_, 0);
        patchVertexBase_ = std::uint32_t(crossings + splitPoints);
        std::copy(split_.points.begin(), split_.points.end(), mesh_.vertices.begin() + std::ptrdiff_t(crossings));
        std::copy(split_.normals.begin(), split_.normals.end(), crossingNormal_.begin() + std::ptrdiff_t(crossings));

        std::atomic<std::size_t> exact{0}, flipped{0};
        VertexCounts placed;
        index_.forEach([&](std::size_t i) { crossingPass(i, exact); });
        index_.forEach([&](std::size_t i) { patchPass(i, placed); });
        splitPatchPass(std::uint32_t(crossings), placed);
        const detail::FlipInputs flips = flipInputs();
        index_.forEach(
            [&](std::size_t i) { flipped += detail::flipChords(flips, index_.blocks[i]); });
        stats.cells = cells;
        stats.crossings = crossings + split_.edgeEnds;
        stats.patches = patches + split_.patches();
        stats.splitCells = split_.cells.size();
        stats.splitEdges = split_.edges.size();
        stats.faceVertices = split_.points.size() - split_.edgeEnds;
        stats.plainCells = plainCells;
        stats.exactCrossings = exact + split_.edgeEnds;
        stats.edgeVertices = placed.edges;
        stats.cornerVertices = placed.corners;
        stats.movedApart = placed.movedApart;
        stats.patchPairsLeftCrossing = placed.pairsLeftCrossing;
        stats.flipped = flipped;
        // Only the mesh is needed from here on: free the rest before the check.
        decltype(crossingNormal_)().swap(crossingNormal_);
        decltype(feature_)().swap(feature_);
        index_ = detail::BlockIndex();
        faceVertexBase_ = std::uint32_t(crossings + split_.edgeEnds);
        faceVertexEnds_.clear();
        for (const auto& [a, b] : split_.faceVertexEnds)
            faceVertexEnds_.push_back({std::uint32_t(crossings) + a, std::uint32_t(crossings) + b});
        decltype(split_.points)().swap(split_.points);
        decltype(split_.normals)().swap(split_.normals);
        decltype(split_.loopIds)().swap(split_.loopIds);
        stats.check = repairAndCheck(stats.pulledBack);
        if (stats.check.facingAgainstTriangles + stats.check.degenerateTriangles > 0 &&
            detail::unflip(mesh_, patchVertexBase_, unrepaired_) > 0) {
            std::size_t more = 0;
            stats.check = repairAndCheck(more);
            stats.pulledBack += more;
        }
        // The passes mesh every cell with surface in the index's blocks, and the index holds all
        // of them unless the level set changes sign between two tiles (BlockIndex::blockAt): a hole
        // in the mesh is where, next to the index, it does.
        if (stats.check.boundaryEdges > 0) {
            detail::BlockIndex all;
            all.find(grid_);
            if (const std::optional<Coord> cell = all.mixedCellOutside(grid_)) throwOutsideBand(*cell);
        }
        findFoldedSplitEdges();
        split_ = detail::SplitCells();
        if (adaptivity_ > 0.0) {
            FlatMergeOptions merge;
            merge.maxAngle = adaptivity_ * kMergeAngle;
            merge.maxDistance = adaptivity_ * kMergeDistance * h_;
            stats.merged = mergeFlatRegions(mesh_, merge);
            stats.check = checkMesh(mesh_);
        }
        return std::move(mesh_);
    }

private:
    // ------------------------------------------------------------------ blocks

    /// The split cells (split_cells.h) and their loops, and per block the bits of its split cells
    /// and of the edges it owns that hold several crossings.
    void findSplit() {
        detail::SplitInputs in;
        in.offset = {offset_.x(), offset_.y(), offset_.z()};
        in.cornerGap = kCornerGap;
        in.featureAngle = featureAngle_;
        const auto acc = grid_.getConstAccessor();
        in.value = [&](const detail::GridPoint& g) { return acc.getValue(Coord(g[0], g[1], g[2])); };
        in.crossing = [&](const detail::GridPoint& g, int a, bool lowerInside) {
            const Coord lower(g[0], g[1], g[2]);
            const Crossing x = findCrossing(lower, a, lowerInside);
            const Vec3 n = x.n.present() && !x.n.sharp() ? x.n.unpack() : Vec3(0.0);
            return std::make_pair((x.p[a] - latticePoint(lower)[a]) / h_, n);
        };
        in.excluded = &excluded_;
        if (!noSplit_) split_ = detail::findSplitCells(stock_, in);
        const auto bitOf = [](const detail::GridPoint& g) {
            const Coord p(g[0], g[1], g[2]);
            return std::make_pair(detail::BlockIndex::blockKey(p), localOffset(p.x(), p.y(), p.z()));
        };
        splitCellBits_.clear();
        splitEdgeBits_.clear();
        for (std::size_t c = 0; c < split_.cells.size(); ++c) {
            auto bit = bitOf(split_.cells[c]);
            bit.second |= int(c) << 9;  // the cell's index above its 9 bits of offset
            splitCellBits_.push_back(bit);
        }
        splitPlaced_.assign(split_.cells.size(), 0);
        for (const auto& [g, a] : split_.edges) {
            auto bit = bitOf(g);
            bit.second += a * kCells;
            splitEdgeBits_.push_back(bit);
        }
        std::sort(splitCellBits_.begin(), splitCellBits_.end());
        std::sort(splitEdgeBits_.begin(), splitEdgeBits_.end());
    }

    /// Where each split patch's vertex and first triangle go: after the table path's in the
    /// block holding its cell's lower corner, or, for cells in no block (they have no surface
    /// of the table path's), from `patchEnd` and `triangleEnd` on.
    void placeSplitPatches(std::uint64_t patchEnd, std::uint64_t triangleEnd) {
        splitPatchVertex_.assign(split_.patches(), 0);
        splitPatchTriangle_.assign(split_.patches(), 0);
        const auto place = [&](std::size_t c, std::uint64_t& vertex, std::uint64_t& triangle) {
            for (std::uint32_t k = split_.cellPatchStart[c]; k < split_.cellPatchStart[c + 1]; ++k) {
                splitPatchVertex_[k] = std::uint32_t(vertex++);
                splitPatchTriangle_[k] = std::uint32_t(triangle);
                triangle += split_.loopStart[k + 1] - split_.loopStart[k];
            }
        };
        // In the order countBlock counted them: by block, then by offset.
        for (std::size_t i = 0; i < splitCellBits_.size();) {
            const std::uint64_t key = splitCellBits_[i].first;
            const std::size_t c0 = std::size_t(splitCellBits_[i].second >> 9);
            if (!splitPlaced_[c0]) {
                for (; i < splitCellBits_.size() && splitCellBits_[i].first == key; ++i) {}
                continue;
            }
            // countBlock of this block placed the cell: the index holds it.
            const Block& b = *index_.blockAt(detail::BlockIndex::blockOrigin(key));
            std::uint64_t vertex = b.patchBase + b.patchBefore.back(), triangle = b.triangleBase + b.tableTriangles;
            for (; i < splitCellBits_.size() && splitCellBits_[i].first == key; ++i)
                place(std::size_t(splitCellBits_[i].second >> 9), vertex, triangle);
        }
        for (std::size_t c = 0; c < split_.cells.size(); ++c)
            if (!splitPlaced_[c]) place(c, patchEnd, triangleEnd);
    }

    /// The bits of `bits` (sorted by block key) in the block at `origin`.
    template <class F>
    static void forBitsOf(const std::vector<std::pair<std::uint64_t, int>>& bits, const Coord& origin, F&& f) {
        const std::uint64_t key = detail::BlockIndex::blockKey(origin);
        for (auto it = std::lower_bound(bits.begin(), bits.end(), std::make_pair(key, 0)); it != bits.end() && it->first == key;
             ++it)
            f(it->second);
    }

    // ------------------------------------------------------------------ pass 1: counts

    void countPass() {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, index_.blocks.size(), 8), [&](const tbb::blocked_range<std::size_t>& r) {
            const auto acc = grid_.getConstAccessor();
            detail::BlockIndex::SignRows rows;
            for (std::size_t i = r.begin(); i < r.end(); ++i) countBlock(index_.blocks[i], acc, rows);
        });
    }

    void countBlock(Block& b, const openvdb::FloatGrid::ConstAccessor& acc, detail::BlockIndex::SignRows& rows) {
        detail::BlockIndex::readSigns(acc, b.origin, rows);
        std::uint32_t patches = 0, triangles = 0;
        b.config.clear();
        b.patchBefore.clear();
        for (int x = 0; x < kDim; ++x) {
            for (int y = 0; y < kDim; ++y) {
                const std::uint64_t shift = std::uint64_t(y * kDim);
                const std::uint16_t r00 = rows[x][y], r10 = rows[x + 1][y], r01 = rows[x][y + 1];
                b.inside[x] |= std::uint64_t(r00 & 0xff) << shift;
                b.owned[x] |= std::uint64_t((r00 ^ r10) & 0xff) << shift;
                b.owned[kDim + x] |= std::uint64_t((r00 ^ r01) & 0xff) << shift;
                b.owned[2 * kDim + x] |= std::uint64_t((r00 ^ (r00 >> 1)) & 0xff) << shift;
                b.mixed[x] |= std::uint64_t(detail::BlockIndex::mixedRow(rows, x, y)) << shift;
            }
        }
        // Edges with several crossings get theirs from the split cells; their cells are split.
        forBitsOf(splitEdgeBits_, b.origin, [&](int bit) { b.owned[bit >> 6] &= ~(std::uint64_t(1) << (bit & 63)); });
        std::uint64_t split[8] = {};
        forBitsOf(splitCellBits_, b.origin, [&](int bit) { split[(bit & 511) >> 6] |= std::uint64_t(1) << (bit & 63); });
        // The mixed cells in rank order (offset order), with their configurations.
        int mixedCells = 0;
        for (int w = 0; w < kCells / 64; ++w) mixedCells += popcount(b.mixed[w]);
        b.config.reserve(std::size_t(mixedCells));
        b.patchBefore.reserve(std::size_t(mixedCells) + 1);
        forEachSetBit(b.mixed, kCells / 64, [&](int off) {
            const int x = off >> 6, y = (off >> 3) & 7, z = off & 7;
            std::uint8_t inside = 0;
            for (int k = 0; k < 8; ++k)
                inside |= std::uint8_t(((rows[x + (k & 1)][y + ((k >> 1) & 1)] >> (z + (k >> 2))) & 1u) << k);
            b.patchBefore.push_back(std::uint16_t(patches));
            if ((split[off >> 6] >> (off & 63)) & 1) {
                b.config.push_back(Block::kSplit);
                return;
            }
            const std::uint8_t joined = joinedFaces(acc, b.origin.offsetBy(x, y, z), inside);
            b.config.push_back(std::uint16_t(inside | (joined << 8)));
            if (plainCell(b.origin.offsetBy(x, y, z), inside)) {
                b.plain[off >> 6] |= std::uint64_t(1) << (off & 63);
                triangles += 2;
                return;
            }
            const CellPatches& p = detail::cellPatches(inside, joined);
            patches += p.count;
            for (int k = 0; k < p.count; ++k) triangles += p.size[k];
        });
        b.patchBefore.push_back(std::uint16_t(patches));
        std::uint32_t n = 0;
        for (int w = 0; w < 24; ++w) {
            b.ownedBefore[w] = std::uint16_t(n);
            n += std::uint32_t(popcount(b.owned[w]));
        }
        std::uint16_t m = 0;
        for (int w = 0; w < 8; ++w) {
            b.mixedBefore[w] = m;
            m = std::uint16_t(m + popcount(b.mixed[w]));
        }
        b.crossings = n;
        b.tableTriangles = triangles;
        forBitsOf(splitCellBits_, b.origin, [&](int bit) {
            const std::size_t c = std::size_t(bit >> 9);
            const std::uint32_t p0 = split_.cellPatchStart[c], p1 = split_.cellPatchStart[c + 1];
            patches += p1 - p0;
            triangles += split_.loopStart[p1] - split_.loopStart[p0];
            splitPlaced_[c] = 1;
        });
        b.patches = patches;
        b.triangles = triangles;
    }

    /// The ambiguous faces of the cell at p whose inside corners the asymptotic decider joins.
    static std::uint8_t joinedFaces(const openvdb::FloatGrid::ConstAccessor& acc, const Coord& p, std::uint8_t inside) {
        const std::uint8_t ambiguous = detail::ambiguousFaces(inside);
        if (!ambiguous) return 0;
        float f[8];
        for (int k = 0; k < 8; ++k) f[k] = acc.getValue(p.offsetBy(k & 1, (k >> 1) & 1, (k >> 2) & 1));
        std::uint8_t joined = 0;
        for (int face = 0; face < detail::kCellFaces; ++face) {
            if (!((ambiguous >> face) & 1)) continue;
            const std::array<int, 4> k = detail::faceCorners(face);
            if (detail::insideJoinedAcrossFace(f[k[0]], f[k[1]], f[k[2]], f[k[3]])) joined |= std::uint8_t(1u << face);
        }
        return joined;
    }

    /// @brief Whether the cell at p is plain: the surface crosses it as one flat square across an
    /// axis a (its four corners on one side of a in material, the other four not), at one height
    /// along a, with one normal, +a or -a, at all four crossings, which are dexel ends. That is a
    /// face of the stock box, or a floor or wall a flat face of a tool made, and two triangles
    /// between the crossings are that square exactly; a patch vertex would have been placed on it
    /// (its crossings' planes are one plane), with four triangles. On the hood at 2 mm three
    /// quarters of the fan triangles lay on the stock box's faces.
    bool plainCell(const Coord& p, std::uint8_t inside) const {
        // Per axis, the corners (bit k: corner k = x + 2y + 4z) on its lower side.
        static constexpr std::uint8_t kLower[3] = {0x55, 0x33, 0x0f};
        int a = 0;
        while (a < 3 && inside != kLower[a] && inside != std::uint8_t(~kLower[a])) ++a;
        if (a == 3) return false;
        const bool in0 = inside == kLower[a];
        // The outward normal is +a with material on the lower side.
        const std::array<std::uint32_t, 4>& outward = axisNormal_[std::size_t(2 * a + (in0 ? 0 : 1))];
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        float first = 0.0f;
        for (int k = 0; k < 4; ++k) {
            Coord lower = p;
            lower[b] += k & 1;
            lower[c] += k >> 1;
            float t = 0.0f;
            PackedNormal n;
            // A normal marked sharp has another packing, and is not taken.
            if (!dexelEnd(lower, a, in0, t, n) || std::find(outward.begin(), outward.end(), n.bits) == outward.end())
                return false;
            if (k == 0) first = t;
            else if (t != first) return false;
        }
        return true;
    }

    // ------------------------------------------------------------------ lookups

    /// The mesh index of the crossing on the edge from lattice point p along axis a, an edge of
    /// the cell at `cell`.
    /// @throw Error (throwOutsideBand) if no block holds p: the sign change lies between tiles.
    std::uint32_t crossingIndex(const detail::BlockIndex::Around& near, const Coord& p, int a, const Coord& cell) const {
        const Block* b = near.at(p);
        if (!b) throwOutsideBand(cell);
        return ownedIndex(*b, p, a);
    }

    /// The mesh index of the crossing that block b owns on the edge from its point p along a.
    static std::uint32_t ownedIndex(const Block& b, const Coord& p, int a) {
        const int bit = a * kCells + localOffset(p.x(), p.y(), p.z());
        return b.crossingBase + b.ownedBefore[bit >> 6] + std::uint32_t(popcountBelow(b.owned[bit >> 6], bit & 63));
    }

    /// Throws the error for the cell at `cell`, which has surface but lies in no block of the index
    /// or has a crossing that lies in none: the level set changes sign between two of its tiles
    /// there, where the band of distances has a hole (BlockIndex::blockAt). No mesh made from the
    /// index would be closed.
    [[noreturn]] void throwOutsideBand(const Coord& cell) const {
        const Vec3 c = latticePoint(cell) + 0.5 * h_;
        char text[400];
        std::snprintf(text, sizeof text,
                      "contouring: the stock's dexel families disagree: the level set changes sign outside its band, "
                      "where no family has a dexel end, at the lattice cell centred at (%.6g, %.6g, %.6g) mm, so no "
                      "closed mesh can be made (a family empty where the others hold material does this, as in a "
                      "stock cast from an open mesh)",
                      c.x, c.y, c.z);
        throw Error(text);
    }

    /// The loop of patch k of the cell at p: its crossings' mesh indices, in order.
    int loopOf(const detail::BlockIndex::Around& near, const Coord& p, const CellPatches& patches, int k, std::uint32_t* out) const {
        const auto& starts = edgeStarts();
        int at = 0;
        for (int j = 0; j < k; ++j) at += patches.size[j];
        const int len = patches.size[k];
        for (int i = 0; i < len; ++i) {
            const EdgeStart& e = starts[patches.edges[at + i]];
            out[i] = crossingIndex(near, p.offsetBy(e.dx, e.dy, e.dz), e.axis, p);
        }
        return len;
    }

    // ------------------------------------------------------------------ pass 2: crossings

    void crossingPass(std::size_t bi, std::atomic<std::size_t>& exactCount) {
        const Block& b = index_.blocks[bi];
        std::size_t exact = 0;
        std::uint32_t at = b.crossingBase;
        for (int a = 0; a < 3; ++a) {
            forEachSetBit(b.owned + a * 8, kCells / 64, [&](int off) {
                const Crossing c = findCrossing(b.origin.offsetBy(off >> 6, (off >> 3) & 7, off & 7), a,
                                                testBit(b.inside, off));
                exact += c.exact;
                mesh_.vertices[at] = c.p;
                crossingNormal_[at] = c.n;
                ++at;
            });
        }
        exactCount += exact;
    }

    static bool testBit(const std::uint64_t* words, int bit) { return (words[bit >> 6] >> (bit & 63)) & 1; }

    /// The world position of the lattice point at grid index g.
    Vec3 latticePoint(const Coord& g) const {
        return lattice_.point(g.x() - offset_.x(), g.y() - offset_.y(), g.z() - offset_.z());
    }

    /// The crossing on the edge from lattice point `lower` along axis a (in0: whether `lower` is
    /// in material; the upper point is not, or the other way round): the dexel's end next to the
    /// point in material (the end of the segment holding the lower point, or the start of the one
    /// holding the upper point). With no dexel there (a family not kept) or one that disagrees
    /// with the level set's vote, the field is interpolated linearly and the normal is unknown.
    Crossing findCrossing(const Coord& lower, int a, bool in0) const {
        const double t0 = (lower[a] - offset_[a] + 0.5) * h_, t1 = t0 + h_;
        Crossing x;
        x.p = latticePoint(lower);
        float end = 0.0f;
        x.exact = dexelEnd(lower, a, in0, end, x.n);
        double t = end;
        if (!x.exact) {
            const auto acc = grid_.getConstAccessor();
            Coord upper = lower;
            upper[a] += 1;
            const double f0 = acc.getValue(lower), f1 = acc.getValue(upper);
            t = t0 + h_ * f0 / (f0 - f1);
        }
        const double gap = kCornerGap * h_;
        t = std::clamp(t, t0 + gap, t1 - gap);
        x.p[a] = lattice_.origin[a] + t;
        return x;
    }

    /// The dexel end on the edge from lattice point `lower` along axis a (in0 as findCrossing's):
    /// its offset t along the dexel and its normal n; false when there is none (a family not
    /// kept, or a dexel that disagrees with the level set's vote).
    bool dexelEnd(const Coord& lower, int a, bool in0, float& t, PackedNormal& n) const {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        // Lattice indexes, as plain integers: a Coord made here (lower - offset_) and indexed by
        // axis had made the count pass, which calls this four times per plain cell, take 2.4
        // times as long on the hood.
        const int la = lower[a] - offset_[a], lb = lower[b] - offset_[b], lc = lower[c] - offset_[c];
        const double t0 = (la + 0.5) * h_, t1 = t0 + h_;
        const Axis axis = axisFromIndex(a);
        if (!stock_.has(axis) || lb < 0 || lc < 0 || lb >= lattice_.n[b] || lc >= lattice_.n[c]) return false;
        const SegmentSpan segs = stock_.family(axis).segments(lb, lc);
        if (in0) {
            // The segment holding t0 ends in (t0, t1].
            const Segment* s = std::partition_point(segs.begin(), segs.end(),
                                                    [t0](const Segment& g) { return double(g.hi) < t0; });
            if (s == segs.end() || !(double(s->lo) <= t0 && double(s->hi) <= t1)) return false;
            t = s->hi;
            n = s->nhi;
            return true;
        }
        // The segment holding t1 starts in [t0, t1].
        const Segment* s = std::partition_point(segs.begin(), segs.end(),
                                                [t1](const Segment& g) { return double(g.hi) <= t1; });
        if (s == segs.end() || !(double(s->lo) <= t1 && double(s->lo) >= t0)) return false;
        t = s->lo;
        n = s->nlo;
        return true;
    }

    // ------------------------------------------------------------------ pass 3: patch vertices

    /// What pass 3 counts (ContourStats): vertices on creases and on corners, vertices moved apart
    /// from another patch's, and pairs of patches left crossing (keepPatchesApart).
    struct VertexCounts {
        std::atomic<std::size_t> edges{0}, corners{0}, movedApart{0}, pairsLeftCrossing{0};
    };

    void patchPass(std::size_t bi, VertexCounts& counts) {
        const Block& b = index_.blocks[bi];
        const detail::BlockIndex::Around near = index_.around(b);
        std::size_t edges = 0, corners = 0, movedApart = 0, leftCrossing = 0;
        std::uint32_t loop[detail::kCellEdges];
        std::uint32_t at = b.patchBase;
        std::uint32_t tri = b.triangleBase;
        b.forEachTableCell([&](int off, const CellPatches& patches) {
            const Coord p = b.origin.offsetBy(off >> 6, (off >> 3) & 7, off & 7);
            if (b.isPlain(off)) {
                // One square (plainCell): its loop is convex and flat, so any diagonal serves.
                loopOf(near, p, patches, 0, loop);
                mesh_.triangles[tri++] = {loop[0], loop[1], loop[2]};
                mesh_.triangles[tri++] = {loop[0], loop[2], loop[3]};
                return;
            }
            detail::SharedPatch shared[detail::kMaxPatches];
            for (int k = 0; k < patches.count; ++k) {
                const int len = loopOf(near, p, patches, k, loop);
                shared[k].vertex = at;
                shared[k].len = len;
                std::copy(loop, loop + len, shared[k].loop);
                int qefRank = 0;
                const detail::PatchVertexRule::Loop crossings{mesh_.vertices.data(), crossingNormal_.data(), loop, len};
                mesh_.vertices[at] = vertexRule_.place(crossings, latticePoint(p), patches.count > 1, qefRank);
                feature_[at - patchVertexBase_] = std::uint8_t(qefRank >= 2);
                edges += qefRank == 2;
                corners += qefRank == 3;
                // The fan; the flip pass turns chords along creases afterwards.
                for (int i = 0; i < len; ++i)
                    mesh_.triangles[tri++] = {at, loop[i], loop[i + 1 == len ? 0 : i + 1]};
                ++at;
            }
            if (patches.count > 1) {
                const detail::PatchesApart apart = detail::keepPatchesApart(
                    shared, patches.count, mesh_.vertices.data(), kFanCrossing * h_);
                movedApart += std::size_t(apart.moved);
                leftCrossing += std::size_t(apart.leftCrossing);
            }
        });
        counts.edges += edges;
        counts.corners += corners;
        counts.movedApart += movedApart;
        counts.pairsLeftCrossing += leftCrossing;
    }

    /// The split cells' patch vertices and fans (split_cells.h), one after another: they are few.
    /// `crossings` is the number of the table path's crossings, after which the split cells' own
    /// vertices lie. Their fans are never flipped.
    void splitPatchPass(std::uint32_t crossings, VertexCounts& counts) {
        std::vector<std::uint32_t> loop;
        for (std::size_t c = 0; c < split_.cells.size(); ++c) {
            const std::uint32_t p0 = split_.cellPatchStart[c], p1 = split_.cellPatchStart[c + 1];
            for (std::uint32_t k = p0; k < p1; ++k)
                placeSplitPatch(k, crossings, p1 - p0 > 1, loop, counts);
        }
    }

    /// Split patch k's vertex and fan (splitPatchPass); `sharesCell`: its cell holds others.
    void placeSplitPatch(std::uint32_t k, std::uint32_t crossings, bool sharesCell,
                         std::vector<std::uint32_t>& loop, VertexCounts& counts) {
        std::uint32_t tri = splitPatchTriangle_[k];
        loop.clear();
        for (std::uint32_t i = split_.loopStart[k]; i < split_.loopStart[k + 1]; ++i) {
            const std::uint32_t id = split_.loopIds[i];
            if (id & detail::SplitCells::kOrdinary) {
                const auto& [g, a] = split_.ordinary[id & ~detail::SplitCells::kOrdinary];
                const Coord lower(g[0], g[1], g[2]);
                const Block* b = index_.blockAt(lower);
                if (!b) throwOutsideBand(Coord(split_.patchCell[k][0], split_.patchCell[k][1], split_.patchCell[k][2]));
                loop.push_back(ownedIndex(*b, lower, a));
            } else {
                loop.push_back(crossings + id);
            }
        }
        const std::uint32_t at = splitPatchVertex_[k];
        const detail::GridPoint& g = split_.patchCell[k];
        int qefRank = 0;
        const int len = int(loop.size());
        const detail::PatchVertexRule::Loop crossingsOf{mesh_.vertices.data(), crossingNormal_.data(), loop.data(), len};
        const Vec3 cellLo = latticePoint(Coord(g[0], g[1], g[2]));
        const Vec3 fitted = vertexRule_.place(crossingsOf, cellLo, sharesCell, qefRank);
        // The bounds place kept the vertex in: its cell, a crease's or corner's kFaceInset inside.
        const double inset = qefRank >= 2 ? detail::PatchVertexRule::kFaceInset * h_ : 0.0;
        const Vec3 ownSide =
            detail::keepOffFinMiddle(split_, k, featureAngle_, cellLo + inset, cellLo + (h_ - inset), fitted);
        mesh_.vertices[at] = detail::keepOffPathFaces(crossingsOf, cellLo, h_, ownSide);
        counts.edges += qefRank == 2;
        counts.corners += qefRank == 3;
        for (int i = 0; i < len; ++i) mesh_.triangles[tri++] = {at, loop[std::size_t(i)], loop[std::size_t(i + 1 == len ? 0 : i + 1)]};
    }

    /// The edges with several crossings of the split cells whose triangles still fold or have no
    /// area after repair, or pass through another patch's of their cell (foldedSplitEdges).
    void findFoldedSplitEdges() {
        foldedSplitEdges_.clear();
        // The split patches by their first triangle.
        std::vector<std::pair<std::uint32_t, std::uint32_t>> byTriangle;
        for (std::uint32_t k = 0; k < split_.patches(); ++k) byTriangle.push_back({splitPatchTriangle_[k], k});
        std::sort(byTriangle.begin(), byTriangle.end());
        std::vector<std::uint32_t> faulty =
            detail::crossingPatchTriangles(split_, mesh_, splitPatchTriangle_, kFanCrossing * h_);
        faulty.insert(faulty.end(), unrepaired_.begin(), unrepaired_.end());
        for (std::uint32_t t : faulty) {
            auto it = std::upper_bound(byTriangle.begin(), byTriangle.end(),
                                       std::make_pair(t, std::numeric_limits<std::uint32_t>::max()));
            if (it == byTriangle.begin()) continue;
            const std::uint32_t k = (--it)->second;
            if (t >= it->first + split_.loopStart[k + 1] - split_.loopStart[k]) continue;
            const detail::GridPoint& cell = split_.patchCell[k];
            for (int e = 0; e < detail::kCellEdges; ++e) {
                const int c0 = detail::edgeCorner(e, 0);
                const std::pair<detail::GridPoint, int> edge{
                    {cell[0] + (c0 & 1), cell[1] + ((c0 >> 1) & 1), cell[2] + ((c0 >> 2) & 1)}, detail::edgeAxis(e)};
                if (std::binary_search(split_.edges.begin(), split_.edges.end(), edge)) foldedSplitEdges_.push_back(edge);
            }
        }
        std::sort(foldedSplitEdges_.begin(), foldedSplitEdges_.end());
        foldedSplitEdges_.erase(std::unique(foldedSplitEdges_.begin(), foldedSplitEdges_.end()), foldedSplitEdges_.end());
    }

    // ------------------------------------------------------------------ pass 4: flips

    /// What the flip pass (detail/flips.h) reads, after pass 3 and the split cells' vertices and
    /// fans, and the lookups it makes.
    detail::FlipInputs flipInputs() {
        detail::FlipInputs in;
        in.index = &index_;
        in.mesh = &mesh_;
        in.patchVertexBase = patchVertexBase_;
        in.crossingNormal = crossingNormal_.data();
        in.feature = feature_.data();
        in.loop = [this](const detail::BlockIndex::Around& near, const Coord& p,
                         const CellPatches& patches, int k,
                         std::uint32_t* out) { return loopOf(near, p, patches, k, out); };
        in.cell = [this](const detail::BlockIndex::Around& near, const Coord& p,
                         const CellPatches*& patches, std::uint32_t& firstPatch) {
            return cellAt(near, p, patches, firstPatch);
        };
        return in;
    }

    /// The mixed cell whose lower corner is p: its patches and the mesh index of its first patch;
    /// false for a plain cell, which has no patch vertex, and for a split cell, whose fans are
    /// never flipped.
    /// @throw Error (throwOutsideBand) if no block holds p.
    bool cellAt(const detail::BlockIndex::Around& near, const Coord& p, const CellPatches*& patches, std::uint32_t& firstPatch) const {
        const Block* held = near.at(p);
        if (!held) throwOutsideBand(p);
        const Block& b = *held;
        const int off = localOffset(p.x(), p.y(), p.z());
        const int rank = b.rankOf(off);
        patches = &b.patchesOf(rank);
        firstPatch = b.patchBase + b.patchBefore[std::size_t(rank)];
        return !b.isPlain(off) && !b.isSplit(rank);
    }

    // ------------------------------------------------------------------ pass 5: folds

    /// The mesh's check, with folds repaired: a triangle facing against its own vertices'
    /// normals (checkMesh's test), nearly so, or without area has its patch vertices pulled
    /// halfway back towards their loops' mass points, round after round, until none is left; at
    /// the last round they go onto the mass points. Crossings, which are exact, never move.
    MeshCheck repairAndCheck(std::size_t& moved) {
        FoldRepair repair;
        repair.minCosine = kFoldMargin;
        repair.rounds = kPullRounds;
        repair.pull = [&](std::uint32_t v, int round, Vec3& x, const std::vector<std::uint32_t>& neighbours) {
            if (v < patchVertexBase_) return false;
            // The patch's loop: its crossings are the vertex's neighbours that are crossings
            // (a flip trades a chord for a join with another patch vertex, keeping both ends).
            Vec3 mass(0.0);
            int n = 0;
            for (std::uint32_t w : neighbours)
                if (w < patchVertexBase_) mass += mesh_.vertices[w], ++n;
            if (n == 0) return false;
            mass /= double(n);
            const Vec3 to = round + 1 >= kPullRounds ? mass : 0.5 * (x + mass);
            if (to == x) return false;
            x = to;
            return true;
        };
        // Still folded after the last round: points of the loop's hull, towards each crossing
        // and each pair of crossings from the mass point. Convex combinations of the crossings,
        // which lie on the cell's edges, stay inside the cell.
        repair.candidates = [&](std::uint32_t v, const std::vector<std::uint32_t>& neighbours, std::vector<Vec3>& out) {
            if (v >= faceVertexBase_ && v < patchVertexBase_) {
                // A split cell's face vertex, an estimate: towards the middle of its lens's chord,
                // staying on its face.
                const auto& ends = faceVertexEnds_[v - faceVertexBase_];
                const Vec3 x = mesh_.vertices[v], mid = 0.5 * (mesh_.vertices[ends[0]] + mesh_.vertices[ends[1]]);
                for (double t : kFaceVertexReach) out.push_back(x + t * (mid - x));
                return;
            }
            if (v < patchVertexBase_) return;
            std::vector<Vec3> loop;
            for (std::uint32_t w : neighbours)
                if (w < patchVertexBase_) loop.push_back(mesh_.vertices[w]);
            if (loop.empty()) return;
            Vec3 mass(0.0);
            for (const Vec3& c : loop) mass += c;
            mass /= double(loop.size());
            out.push_back(mass);
            for (std::size_t i = 0; i < loop.size(); ++i) {
                for (double t : kCandidateReach) out.push_back(mass + t * (loop[i] - mass));
                for (std::size_t j = i + 1; j < loop.size(); ++j)
                    for (double t : kCandidateReach) out.push_back(mass + t * (0.5 * (loop[i] + loop[j]) - mass));
            }
        };
        return repairAndCheckMesh(mesh_, repair, &moved, &unrepaired_);
    }

    const openvdb::FloatGrid& grid_;
    const TriDexelStock& stock_;
    const Lattice& lattice_;
    Coord offset_;  ///< the grid index of lattice point (0, 0, 0); the passes work in grid indexes
    double h_;
    double featureAngle_;
    detail::PatchVertexRule vertexRule_;
    double adaptivity_ = 0.0;
    /// Per axis a and side (2 a for +a, 2 a + 1 for -a), the packings of that unit normal, not
    /// marked sharp: the other components +0 or -0, which the octahedral square folds to its four
    /// corners for -z (and to one code otherwise).
    std::array<std::array<std::uint32_t, 4>, 6> axisNormal_{};
    detail::BlockIndex index_;
    Mesh mesh_;
    std::vector<PackedNormal, NoZeroAllocator<PackedNormal>> crossingNormal_;
    std::vector<std::uint8_t, NoZeroAllocator<std::uint8_t>> feature_;
    std::uint32_t patchVertexBase_ = 0;
    std::vector<std::uint32_t> unrepaired_;
    detail::SplitCells split_;
    /// Per split cell and per edge with several crossings: (block key, bit in that block's words).
    std::vector<std::pair<std::uint64_t, int>> splitCellBits_, splitEdgeBits_;
    /// Per split cell, whether a block holds it (countBlock); the patches and triangles of those
    /// no block holds; per split patch, its vertex and first triangle (placeSplitPatches).
    std::vector<std::uint8_t> splitPlaced_;
    std::uint64_t unplacedPatches_ = 0, unplacedTriangles_ = 0;
    std::vector<std::uint32_t> splitPatchVertex_, splitPatchTriangle_;
    /// The split cells' face vertices: their first mesh index, and per face vertex its two ends.
    std::uint32_t faceVertexBase_ = 0;
    std::vector<std::array<std::uint32_t, 2>> faceVertexEnds_;
    /// Edges the general path leaves to the table path (contourStock's retries), sorted; all when
    /// `noSplit_`.
    std::vector<std::pair<detail::GridPoint, int>> excluded_, foldedSplitEdges_;
    bool noSplit_ = false;
};

}  // namespace

Mesh contourStock(const LevelSet& levelSet, const TriDexelStock& stock, const ContourOptions& options,
                  ContourStats* stats) {
    openvdb::FloatGrid::ConstPtr grid = gridOf(levelSet);
    if (!grid) throw Error("contouring: the level set holds no grid");
    const std::optional<Lattice> lat = levelSet.lattice();
    const Lattice& own = stock.lattice();
    if (!lat || lat->n != own.n || std::abs(lat->h - own.h) > 1e-12 * own.h ||
        glm::length(lat->origin - own.origin) > 1e-9 * std::max(1.0, glm::length(own.origin)))
        throw Error("contouring: the level set was not rebuilt from this stock's lattice");
    // Split cells whose triangles fold are left to the table path, and the mesh made again: after
    // kSplitRetries runs with folds there, without any split cells (the mesh of before they were).
    std::vector<std::pair<detail::GridPoint, int>> excluded;
    std::size_t found = 0;
    for (int run = 0;; ++run) {
        ContourStats local;
        Contourer c(*grid, stock, options, excluded, run > kSplitRetries);
        Mesh mesh = c.run(local);
        if (run == 0) found = local.splitEdges;
        if (c.foldedSplitEdges().empty() || run > kSplitRetries) {
            local.splitRuns = run + 1;
            local.splitEdgesDropped = found - local.splitEdges;
            if (stats) *stats = local;
            return mesh;
        }
        excluded.insert(excluded.end(), c.foldedSplitEdges().begin(), c.foldedSplitEdges().end());
        std::sort(excluded.begin(), excluded.end());
    }
}

}  // namespace dexelmill
