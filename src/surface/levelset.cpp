#include "dexelmill/surface/levelset.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "dexelmill/error.h"
#include "dexelmill/surface/levelset_vdb.h"
#include "surface/detail/grid_meta.h"

namespace dexelmill {

// ---------------------------------------------------------------------------------------------
// The handle

LevelSet::LevelSet() = default;
LevelSet::~LevelSet() = default;
LevelSet::LevelSet(const LevelSet&) = default;
LevelSet& LevelSet::operator=(const LevelSet&) = default;
LevelSet::LevelSet(LevelSet&&) noexcept = default;
LevelSet& LevelSet::operator=(LevelSet&&) noexcept = default;
LevelSet::LevelSet(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}

namespace {

const openvdb::FloatGrid& requireGrid(const std::shared_ptr<LevelSet::Impl>& impl) {
    if (!impl || !impl->grid) throw Error("level set: the handle holds no grid");
    return *impl->grid;
}

}  // namespace

double LevelSet::voxelSize() const { return requireGrid(impl_).voxelSize()[0]; }

double LevelSet::halfWidth() const {
    const openvdb::FloatGrid& g = requireGrid(impl_);
    return double(g.background()) / g.voxelSize()[0];
}

std::size_t LevelSet::activeVoxelCount() const {
    return std::size_t(requireGrid(impl_).activeVoxelCount());
}

std::size_t LevelSet::leafCount() const { return std::size_t(requireGrid(impl_).tree().leafCount()); }

std::size_t LevelSet::memoryBytes() const { return std::size_t(requireGrid(impl_).memUsage()); }

Box LevelSet::activeBounds() const {
    const openvdb::FloatGrid& g = requireGrid(impl_);
    openvdb::CoordBBox bbox;
    if (!g.tree().evalActiveVoxelBoundingBox(bbox)) return Box::empty();
    const openvdb::Vec3d lo = g.indexToWorld(bbox.min()), hi = g.indexToWorld(bbox.max());
    Box b;
    b.expand(Vec3(lo.x(), lo.y(), lo.z()));
    b.expand(Vec3(hi.x(), hi.y(), hi.z()));
    return b;
}

std::string LevelSet::source() const {
    const openvdb::FloatGrid& g = requireGrid(impl_);
    const auto meta = g.getMetadata<openvdb::StringMetadata>(detail::kMetaSource);
    return meta ? meta->value() : std::string();
}

std::optional<Lattice> LevelSet::lattice() const {
    return detail::latticeFromMeta(requireGrid(impl_));
}

double LevelSet::valueAt(const Vec3& world) const {
    const openvdb::FloatGrid& g = requireGrid(impl_);
    openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(g);
    return double(sampler.wsSample(openvdb::Vec3d(world.x, world.y, world.z)));
}

float LevelSet::voxelValue(int i, int j, int k) const {
    const openvdb::FloatGrid& g = requireGrid(impl_);
    const std::array<int, 3> off = detail::latticeOffset(g);
    return g.tree().getValue(openvdb::Coord(i + off[0], j + off[1], k + off[2]));
}

void ensureOpenVdbInitialized() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::FloatGrid::ConstPtr gridOf(const LevelSet& levelSet) {
    return levelSet.impl() ? openvdb::FloatGrid::ConstPtr(levelSet.impl()->grid) : nullptr;
}

LevelSet levelSetFromGrid(openvdb::FloatGrid::Ptr grid) {
    if (!grid) throw Error("level set: null grid");
    if (grid->getGridClass() != openvdb::GRID_LEVEL_SET &&
        grid->getGridClass() != openvdb::GRID_UNKNOWN)
        throw Error("level set: grid '" + grid->getName() + "' is not a level set");
    if (!grid->hasUniformVoxels() || !grid->transform().isLinear())
        throw Error("level set: grid '" + grid->getName() + "' needs a uniform linear transform");
    if (!(grid->background() > 0.0f))
        throw Error("level set: grid '" + grid->getName() + "' has a non-positive background");
    detail::latticeOffset(*grid);  // throws if a recorded lattice does not sit on the voxels
    auto impl = std::make_shared<LevelSet::Impl>();
    impl->grid = std::move(grid);
    return LevelSet(std::move(impl));
}

// ---------------------------------------------------------------------------------------------
// The rebuild (method.md section 7)

namespace {

using LeafT = openvdb::FloatTree::LeafNodeType;
constexpr int kLeafLog2 = 3;  // openvdb::FloatTree leaves are 8^3 voxels
constexpr int kLeafDim = 1 << kLeafLog2;
static_assert(LeafT::DIM == kLeafDim, "FloatTree leaves must be 8^3");

/// floor(i / 8) for negative i too.
inline int blockOf(int i) { return (i >= 0 ? i : i - (kLeafDim - 1)) / kLeafDim; }

/// For the `count` (at most 32) lattice points t = (i0 + m + 1/2) h, m = 0..count-1, along one
/// dexel: whether each is in material (bit m of `inside`) and, if some segment endpoint lies within
/// `reach` of one of them, each one's distance to the nearest endpoint (infinity if the dexel is
/// empty). Returns whether it did: with no endpoint that close every distance exceeds `reach`, the
/// points all lie on the same side, and `dist` is left alone. Endpoints alternate lo, hi, lo, hi
/// ...: a point is in material when an odd number of them lie at or below it.
inline bool scanDexel(const SegmentSpan& segs, int i0, double h, double reach, double* dist, std::uint32_t& inside,
                      int count) {
    const std::size_t ends = 2 * segs.size;
    auto endpoint = [&](std::size_t k) -> double {
        const Segment& s = segs.data[k >> 1];
        return (k & 1) ? s.hi : s.lo;
    };
    const double t0 = (i0 + 0.5) * h;
    // First endpoint above t0: binary search over the sorted endpoints.
    std::size_t lo = 0, hi = ends;
    while (lo < hi) {
        const std::size_t mid = (lo + hi) / 2;
        if (endpoint(mid) <= t0) lo = mid + 1; else hi = mid;
    }
    std::size_t k = lo;
    // The same comparisons as the loop below makes for its first and last points.
    const double tLast = (i0 + count - 1 + 0.5) * h;
    if ((k == 0 || t0 - endpoint(k - 1) > reach) && (k == ends || endpoint(k) - tLast > reach)) {
        inside = (k & 1) ? std::uint32_t((std::uint64_t(1) << count) - 1) : 0u;
        return false;
    }
    constexpr double inf = std::numeric_limits<double>::infinity();
    double t[32];
    for (int m = 0; m < count; ++m) {
        t[m] = (i0 + m + 0.5) * h;
        dist[m] = inf;
    }
    // Only these endpoints can be a point's nearest: the last at or below t0 (every point lies
    // above it), those in (t0, tLast], and the first above tLast (every point lies below it).
    // Each one above t0 turns the points at or above it in or out of material.
    std::uint32_t bits = (k & 1) ? std::uint32_t((std::uint64_t(1) << count) - 1) : 0u;
    for (std::size_t j = k > 0 ? k - 1 : 0; j < ends; ++j) {
        const double e = endpoint(j);
        for (int m = 0; m < count; ++m) dist[m] = std::min(dist[m], std::abs(t[m] - e));
        if (j < k) continue;
        std::uint32_t reached = 0;
        for (int m = 0; m < count; ++m) reached |= std::uint32_t(e <= t[m]) << m;
        bits ^= reached;
        if (e > tLast) break;
    }
    inside = bits;
    return true;
}

/// Bit m of a byte moved to bit 8 m of a word, for every m.
struct ByteSpread {
    std::uint64_t word[256];
    constexpr ByteSpread() : word() {
        for (int b = 0; b < 256; ++b)
            for (int m = 0; m < 8; ++m)
                if ((b >> m) & 1) word[b] |= std::uint64_t(1) << (8 * m);
    }
};
constexpr ByteSpread kByteSpread;

/// Sets, in a leaf's bit mask of its points (word x, bit y * 8 + z: bit `offset` of the leaf's
/// x * 64 + y * 8 + z), the points of the dexel along axis a at (u, v) along axes (a + 1) % 3 and
/// (a + 2) % 3 whose bit m in `bits` (the point m along a) is set.
inline void depositRow(std::uint64_t* words, int a, int u, int v, std::uint32_t bits) {
    if (a == 2) {  // x = u, y = v, z = m
        words[u] |= std::uint64_t(bits) << (8 * v);
    } else if (a == 1) {  // z = u, x = v, y = m
        words[v] |= kByteSpread.word[bits] << u;
    } else {  // y = u, z = v, x = m
        for (int m = 0; m < kLeafDim; ++m) words[m] |= std::uint64_t((bits >> m) & 1u) << (8 * u + v);
    }
}

/// Per four bits: the float sign bit in each lane whose bit is set.
struct SignLanes {
    std::uint32_t lane[16][4];
    constexpr SignLanes() : lane() {
        for (int b = 0; b < 16; ++b)
            for (int m = 0; m < 4; ++m) lane[b][m] = (b >> m) & 1 ? 0x80000000u : 0u;
    }
};
constexpr SignLanes kSignLanes;

/// The values of a leaf's row of eight points from their sums q of inverse squared axis
/// distances: 1 / sqrt(q) within the band (q above `limit`), `background` beyond it, negated
/// where bit m of `signs` is set (the point is in material). Returns the bits of the points
/// within the band. -(1 / sqrt(q)) is the same float as -1 / sqrt(q), so the values are those
/// of a point-by-point loop, four at a time.
inline std::uint32_t bandRow(const float* q, float limit, float background, std::uint32_t signs, float* out) {
#if defined(__SSE2__)
    const __m128 lim = _mm_set1_ps(limit), one = _mm_set1_ps(1.0f), far = _mm_set1_ps(background);
    std::uint32_t on = 0;
    for (int half = 0; half < 2; ++half) {
        const __m128 v = _mm_loadu_ps(q + 4 * half);
        const __m128 in = _mm_cmpgt_ps(v, lim);
        const __m128 magnitude = _mm_or_ps(_mm_and_ps(in, _mm_div_ps(one, _mm_sqrt_ps(v))), _mm_andnot_ps(in, far));
        const __m128 sign =
            _mm_castsi128_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(kSignLanes.lane[(signs >> (4 * half)) & 0xfu])));
        _mm_storeu_ps(out + 4 * half, _mm_xor_ps(magnitude, sign));
        on |= std::uint32_t(_mm_movemask_ps(in)) << (4 * half);
    }
    return on;
#else
    std::uint32_t on = 0;
    for (int m = 0; m < 8; ++m) {
        const bool in = q[m] > limit;
        const float magnitude = in ? 1.0f / std::sqrt(q[m]) : background;
        out[m] = (signs >> m) & 1u ? -magnitude : magnitude;
        on |= std::uint32_t(in) << m;
    }
    return on;
#endif
}

/// The rebuild of one stock; see rebuildLevelSet.
class Rebuilder {
public:
    Rebuilder(const TriDexelStock& stock, const RebuildOptions& options)
        : stock_(stock), lattice_(stock.lattice()), h_(lattice_.h) {
        for (int a = 0; a < 3; ++a) {
            const Axis axis = axisFromIndex(a);
            if (options.families.has(axis) && stock.has(axis)) axes_[axisCount_++] = a;
        }
        if (axisCount_ == 0)
            throw Error("level set rebuild: none of the families '" + options.families.str() +
                        "' is kept by the stock ('" + stock.families().str() + "')");
        // The tie of two votes goes to z, else x: put that axis first.
        std::sort(axes_, axes_ + axisCount_, [](int x, int y) { return (x + 1) % 3 > (y + 1) % 3; });
        width_ = options.halfWidth * h_;
        w2_ = float(1.0 / (width_ * width_));
        // A point with phi < w has an axis distance below sqrt(3) w (equality for a surface at
        // equal angles to the three axes), so it lies that close to a crossing on its own dexel.
        reach_ = std::sqrt(3.0) * width_;
        // Crossings farther than this along an axis belong to other surfaces, not to the local
        // plane the estimate assumes; dropping them costs at most 1/12 of the relative weight
        // of a plane's axis term, and only near the band's edge.
        cutoff_ = 2.0 * reach_;
        if (options.indexOffset) {
            for (int a = 0; a < 3; ++a) {
                off_[a] = (*options.indexOffset)[std::size_t(a)];
                if (off_[a] < 0 || off_[a] >= kLeafDim)
                    throw Error("level set rebuild: index offset " + std::to_string(off_[a]) + " is outside 0..7");
            }
        } else {
            chooseOffsets();
        }
        const int pad = int(std::ceil(reach_ / h_)) + 1;
        for (int a = 0; a < 3; ++a) {
            blockLo_[a] = blockOf(off_[a] - pad);
            blockN_[a] = blockOf(off_[a] + lattice_.n[a] - 1 + pad) - blockLo_[a] + 1;
        }
    }

    /// The grid index of lattice point (0, 0, 0).
    std::array<int, 3> offset() const { return {off_[0], off_[1], off_[2]}; }

    openvdb::FloatGrid::Ptr run() {
        const float background = float(width_);
        auto grid = openvdb::FloatGrid::create(background);
        markBlocks();
        std::vector<std::size_t> blocks;
        for (std::size_t b = 0; b < marks_.size(); ++b)
            if (marks_[b].load(std::memory_order_relaxed)) blocks.push_back(b);
        std::vector<std::atomic<std::uint8_t>>().swap(marks_);

        std::vector<LeafT*> leaves(blocks.size(), nullptr);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 16),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t i = r.begin(); i < r.end(); ++i)
                                  leaves[i] = buildLeaf(blocks[i], background);
                          });
        openvdb::FloatTree& tree = grid->tree();
        for (LeafT* leaf : leaves)
            if (leaf) tree.addLeaf(leaf);
        // Every leaf's inactive voxels already carry +-background; this sets the tiles between
        // the leaves: inside the closed band -background, outside +background.
        openvdb::tools::signedFloodFill(tree);
        return grid;
    }

private:
    std::size_t blockIndex(int bx, int by, int bz) const {
        return std::size_t(bx - blockLo_[0]) +
               std::size_t(blockN_[0]) * (std::size_t(by - blockLo_[1]) +
                                          std::size_t(blockN_[1]) * std::size_t(bz - blockLo_[2]));
    }

    /// Every kOffsetSample-th dexel of a family, in both directions across it, takes part in the
    /// choice of offsets: flat faces, which the choice is for, fill whole rows of dexels.
    static constexpr int kOffsetSample = 4;
    /// A block buildLeaf visits costs about as much to compute whether or not it becomes a leaf;
    /// a leaf adds its memory (2 KiB, first written) and its share of the flood fill and the
    /// mesher's reading. On bear, where the leaves' memory is small, visits counted for more:
    /// the offset with 600 more visits and 1,150 fewer leaves took longer. Hence a visit weighs
    /// twice a leaf.
    static constexpr int kVisitWeight = 2;

    /// Per kept axis a, the offset (0..7) with the fewest blocks along a filled by the sampled
    /// ends on a's dexels: each end's band (the points within width_ of it, which a flat face
    /// across a puts into leaves) and its reach (the points markBlocks marks, whose blocks
    /// buildLeaf visits). Six band points fit in one block at three phases of eight, and the ten
    /// or eleven points of the reach in two at seven or six. Other axes keep 0. The counts are
    /// whole numbers summed in a fixed order: the choice does not depend on the thread count.
    void chooseOffsets() {
        const double band = width_ / h_;
        for (int ai = 0; ai < axisCount_; ++ai) {
            const int a = axes_[ai];
            const DexelFamily& fam = stock_.family(axisFromIndex(a));
            std::uint64_t blocks[kLeafDim] = {};
            for (int ic = 0; ic < fam.nc(); ic += kOffsetSample)
                for (int ib = 0; ib < fam.nb(); ib += kOffsetSample)
                    for (const Segment& s : fam.segments(ib, ic))
                        for (double e : {double(s.lo), double(s.hi)}) {
                            const double x = e / h_ - 0.5;  // e in lattice indexes
                            const int b0 = int(std::floor(x - band)) + 1, b1 = int(std::ceil(x + band)) - 1;
                            const auto [r0, r1] = markedRange(e, lattice_.n[a]);
                            for (int o = 0; o < kLeafDim; ++o)
                                blocks[o] += std::uint64_t(blockOf(b1 + o) - blockOf(b0 + o) + 1 +
                                                           kVisitWeight * (blockOf(r1 + o) - blockOf(r0 + o) + 1));
                        }
            off_[a] = int(std::min_element(blocks, blocks + kLeafDim) - blocks);
        }
    }

    /// The lattice points along an a-dexel (n of them) whose blocks an end e on it marks: those
    /// within reach_ of e, except beyond the lattice along a, where only those within the band.
    /// A point there lies on no dexel of the other families, so its value is its distance along
    /// a alone (reach_ allows for three axes' distances combining), and beyond a face of the
    /// stock box the marks end with the band. The points are tested with the rebuild's own
    /// arithmetic (scanDexel's distance, buildLeaf's float sum, bandRow's comparison), the
    /// distance taken kFusedSlack smaller: where the compiler fuses scanDexel's (i + 1/2) h - e
    /// into one multiply-add, or this one, the two differ by at most an ulp of it, so no band
    /// point is left out; only points that near the band's edge are marked the more. Segment
    /// ends never leave the stock's box (cuts only remove), so these indexes lie within the
    /// lattice's n, which Lattice::fromBox keeps below INT_MAX / 2.
    std::pair<int, int> markedRange(double e, int n) const {
        int i0 = int(std::ceil((e - reach_) / h_ - 0.5));
        int i1 = int(std::floor((e + reach_) / h_ - 0.5));
        auto inBand = [&](int i) {
            const double d = std::max(std::abs((i + 0.5) * h_ - e) * (1.0 - kFusedSlack), kMinDistance * h_);
            return float(1.0 / (d * d)) > w2_;
        };
        if (i0 < 0) {
            int i = 0;
            while (i > i0 && inBand(i - 1)) --i;
            i0 = i;
        }
        if (i1 >= n) {
            int i = n - 1;
            while (i < i1 && inBand(i + 1)) ++i;
            i1 = i;
        }
        return {i0, i1};
    }

    /// Marks every 8^3 block holding a lattice point within reach_ of a crossing on its dexel
    /// (markedRange).
    void markBlocks() {
        marks_ = std::vector<std::atomic<std::uint8_t>>(std::size_t(blockN_[0]) * blockN_[1] *
                                                        blockN_[2]);
        for (int ai = 0; ai < axisCount_; ++ai) {
            const int a = axes_[ai], b = (a + 1) % 3, c = (a + 2) % 3;
            const DexelFamily& fam = stock_.family(axisFromIndex(a));
            tbb::parallel_for(tbb::blocked_range<int>(0, fam.nc()), [&](const tbb::blocked_range<int>& r) {
                for (int ic = r.begin(); ic < r.end(); ++ic) {
                    for (int ib = 0; ib < fam.nb(); ++ib) {
                        int blk3[3];
                        blk3[b] = blockOf(ib + off_[b]);
                        blk3[c] = blockOf(ic + off_[c]);
                        int lastBlock = std::numeric_limits<int>::min();
                        for (const Segment& s : fam.segments(ib, ic)) {
                            for (double e : {double(s.lo), double(s.hi)}) {
                                const auto [i0, i1] = markedRange(e, lattice_.n[a]);
                                const int last = blockOf(i1 + off_[a]);
                                for (int blk = std::max(blockOf(i0 + off_[a]), lastBlock); blk <= last; ++blk) {
                                    blk3[a] = blk;
                                    marks_[blockIndex(blk3[0], blk3[1], blk3[2])].store(1, std::memory_order_relaxed);
                                }
                                lastBlock = last;
                            }
                        }
                    }
                }
            });
        }
        markMissingAxisWalls();
    }

    /// With fewer than three families, a surface across a missing axis (a wall of a z-only stock)
    /// has no crossing on any kept dexel near it: it shows only as neighbouring dexels that
    /// disagree. Marks the blocks around every stretch where a dexel and its neighbour along a
    /// missing axis differ (a missing neighbour beyond the lattice counts as empty).
    void markMissingAxisWalls() {
        for (int ai = 0; ai < axisCount_; ++ai) {
            const int a = axes_[ai], b = (a + 1) % 3, c = (a + 2) % 3;
            const DexelFamily& fam = stock_.family(axisFromIndex(a));
            for (int step = 0; step < 2; ++step) {
                const int across = step == 0 ? b : c;  // the neighbour's direction
                if (hasAxis(across)) continue;
                const int nb = fam.nb(), nc = fam.nc();
                tbb::parallel_for(tbb::blocked_range<int>(-1, nc), [&](const tbb::blocked_range<int>& r) {
                    for (int ic = r.begin(); ic < r.end(); ++ic) {
                        for (int ib = -1; ib < nb; ++ib) {
                            const int jb = step == 0 ? ib + 1 : ib, jc = step == 0 ? ic : ic + 1;
                            if (step == 0 ? ic < 0 : ib < 0) continue;
                            auto segsAt = [&](int x, int y) {
                                return (x >= 0 && x < nb && y >= 0 && y < nc) ? fam.segments(x, y) : SegmentSpan{};
                            };
                            const SegmentSpan s1 = segsAt(ib, ic), s2 = segsAt(jb, jc);
                            if (s1.empty() && s2.empty()) continue;
                            forEachDifference(s1, s2, [&](double t0, double t1) {
                                const int i0 = int(std::ceil(t0 / h_ - 0.5)) - 1;
                                const int i1 = int(std::floor(t1 / h_ - 0.5)) + 1;
                                for (const auto& [x, y] : {std::pair{ib, ic}, std::pair{jb, jc}}) {
                                    int p[3];
                                    p[b] = x;
                                    p[c] = y;
                                    // p[a]: the lattice index of each block's first point.
                                    for (int blk = blockOf(i0 + off_[a]); blk <= blockOf(i1 + off_[a]); ++blk) {
                                        p[a] = blk * kLeafDim - off_[a];
                                        markPoint(p);
                                    }
                                }
                            });
                        }
                    }
                });
            }
        }
    }

    /// Calls f(t0, t1) for each stretch where exactly one of two dexels is in material.
    template <class F>
    static void forEachDifference(const SegmentSpan& s1, const SegmentSpan& s2, F&& f) {
        std::size_t i = 0, j = 0;
        const std::size_t n1 = 2 * s1.size, n2 = 2 * s2.size;
        auto end1 = [&](std::size_t k) { return double((k & 1) ? s1[k >> 1].hi : s1[k >> 1].lo); };
        auto end2 = [&](std::size_t k) { return double((k & 1) ? s2[k >> 1].hi : s2[k >> 1].lo); };
        bool differ = false;
        double start = 0.0;
        while (i < n1 || j < n2) {
            double t;
            if (j >= n2 || (i < n1 && end1(i) <= end2(j))) t = end1(i++);
            else t = end2(j++);
            const bool now = ((i & 1) != 0) != ((j & 1) != 0);
            if (now && !differ) start = t;
            if (!now && differ) f(start, t);
            differ = now;
        }
    }

    /// Marks the block of lattice point p if it lies in the padded block range.
    void markPoint(const int* p) {
        int blk[3];
        for (int k = 0; k < 3; ++k) {
            blk[k] = blockOf(p[k] + off_[k]);
            if (blk[k] < blockLo_[k] || blk[k] >= blockLo_[k] + blockN_[k]) return;
        }
        marks_[blockIndex(blk[0], blk[1], blk[2])].store(1, std::memory_order_relaxed);
    }

    bool hasAxis(int a) const {
        for (int k = 0; k < axisCount_; ++k)
            if (axes_[k] == a) return true;
        return false;
    }

    /// The leaf of block `index`, or null if none of its points is within the band.
    LeafT* buildLeaf(std::size_t index, float background) const {
        int o[3];
        o[0] = int(index % blockN_[0]);
        o[1] = int((index / blockN_[0]) % blockN_[1]);
        o[2] = int(index / (std::size_t(blockN_[0]) * blockN_[1]));
        // o: the leaf's origin in grid indexes; l: its first point's lattice indexes.
        int l[3];
        for (int a = 0; a < 3; ++a) {
            o[a] = (o[a] + blockLo_[a]) * kLeafDim;
            l[a] = o[a] - off_[a];
        }

        constexpr int kSize = LeafT::SIZE;
        float invSq[kSize];  // sum over axes of d_a^-2
        std::fill(invSq, invSq + kSize, 0.0f);
        // Per family (in axes_ order), whether each of the leaf's points is in material: a bit
        // per point at its offset in the leaf, x * 64 + y * 8 + z.
        std::uint64_t in[3][kLeafDim] = {};
        // With fewer than three families the first family's bits on a ring of dexels around the
        // leaf as well, one point beyond it at each end, so that the neighbours across a missing
        // axis are known: [u + 1][v + 1], bit m + 1, for the point m along the family's axis on
        // its dexel (u, v).
        std::uint16_t firstRows[kLeafDim + 2][kLeafDim + 2];
        double dist[kLeafDim + 2];
        // LeafNode offset of (x, y, z) within the leaf: x * 64 + y * 8 + z.
        constexpr int kStride[3] = {kLeafDim * kLeafDim, kLeafDim, 1};
        const int ring = axisCount_ < 3 ? 1 : 0;
        const double minDistance = kMinDistance * h_;
        for (int ai = 0; ai < axisCount_; ++ai) {
            const int a = axes_[ai], b = (a + 1) % 3, c = (a + 2) % 3;
            const DexelFamily& fam = stock_.family(axisFromIndex(a));
            const int r = ai == 0 ? ring : 0;  // only the first family's ring is read
            for (int v = -r; v < kLeafDim + r; ++v) {
                for (int u = -r; u < kLeafDim + r; ++u) {
                    const int ib = l[b] + u, ic = l[c] + v;
                    SegmentSpan segs;
                    if (ib >= 0 && ib < fam.nb() && ic >= 0 && ic < fam.nc())
                        segs = fam.segments(ib, ic);
                    std::uint32_t bits = 0;
                    const bool near = scanDexel(segs, l[a] - r, h_, cutoff_, dist, bits, kLeafDim + 2 * r);
                    if (r) firstRows[u + 1][v + 1] = std::uint16_t(bits);
                    if (u < 0 || u >= kLeafDim || v < 0 || v >= kLeafDim) continue;
                    depositRow(in[ai], a, u, v, (bits >> r) & 0xffu);
                    if (!near) continue;
                    const int start = u * kStride[b] + v * kStride[c];
                    for (int m = 0; m < kLeafDim; ++m) {
                        const double d = std::max(dist[m + r], minDistance);
                        if (d <= cutoff_) invSq[start + m * kStride[a]] += float(1.0 / (d * d));
                    }
                }
            }
        }
        // The majority of the families' votes; a tie of two goes to the first family, so with
        // one or two families a point is in material when the first family says so.
        std::uint64_t inside[kLeafDim];
        for (int w = 0; w < kLeafDim; ++w)
            inside[w] = axisCount_ == 3 ? (in[0][w] & in[1][w]) | (in[0][w] & in[2][w]) | (in[1][w] & in[2][w])
                                        : in[0][w];
        // Across a missing axis the crossing between two disagreeing neighbours is taken at the
        // midpoint: a distance of h/2.
        if (axisCount_ < 3) {
            const int a = axes_[0], b = (a + 1) % 3, c = (a + 2) % 3;
            auto firstAt = [&](const int* q) {  // q: a point of the leaf or its ring, leaf coordinates
                return (firstRows[q[b] + 1][q[c] + 1] >> (q[a] + 1)) & 1u;
            };
            const float wall = float(4.0 / (h_ * h_));
            for (int x = 0; x < kLeafDim; ++x)
                for (int y = 0; y < kLeafDim; ++y)
                    for (int z = 0; z < kLeafDim; ++z) {
                        const int q[3] = {x, y, z};
                        const std::uint32_t here = firstAt(q);
                        for (int mm = 0; mm < 3; ++mm) {
                            if (hasAxis(mm)) continue;
                            int lo[3] = {x, y, z}, hi[3] = {x, y, z};
                            --lo[mm];
                            ++hi[mm];
                            if (firstAt(lo) != here || firstAt(hi) != here)
                                invSq[x * kStride[0] + y * kStride[1] + z * kStride[2]] += wall;
                        }
                    }
        }

        // A point is within the band when its sum exceeds w2. A block with none (one the marks
        // could not rule out, such as the one beyond a flat face's band) gets no leaf, tested
        // before a leaf is made.
        const float w2 = w2_;
        float most = 0.0f;
        for (float q : invSq) most = std::max(most, q);
        if (!(most > w2)) return nullptr;

        auto* leaf = new LeafT(openvdb::Coord(o[0], o[1], o[2]), background, false);
        float* values = leaf->buffer().data();
        // Within the band a point gets its distance estimate, signed, and is active; beyond it
        // +-background. Row by row along z (offsets x * 64 + y * 8 + z).
        LeafT::NodeMaskType active;
        for (int x = 0; x < kLeafDim; ++x) {
            std::uint64_t on = 0;
            for (int y = 0; y < kLeafDim; ++y) {
                const int off = x * kStride[0] + y * kStride[1];
                const auto signs = std::uint32_t(inside[x] >> (kLeafDim * y)) & 0xffu;
                on |= std::uint64_t(bandRow(invSq + off, w2, background, signs, values + off)) << (kLeafDim * y);
            }
            active.template getWord<std::uint64_t>(openvdb::Index(x)) = on;
        }
        leaf->setValueMask(active);
        return leaf;
    }

    /// Axis distances are clamped below at this fraction of h, so that a point on a crossing
    /// gets a tiny non-zero value instead of a division by zero.
    static constexpr double kMinDistance = 1e-6;
    /// Relative: four times an ulp of a distance (markedRange).
    static constexpr double kFusedSlack = 4.0 * std::numeric_limits<double>::epsilon();

    const TriDexelStock& stock_;
    const Lattice& lattice_;
    double h_;
    int axes_[3] = {0, 0, 0};
    int axisCount_ = 0;
    double width_ = 0.0, reach_ = 0.0, cutoff_ = 0.0;
    float w2_ = 0.0f;  ///< a point is within the band when its sum of inverse squares exceeds this
    int off_[3] = {0, 0, 0};  ///< the grid index of lattice point (0, 0, 0)
    int blockLo_[3] = {0, 0, 0}, blockN_[3] = {0, 0, 0};
    std::vector<std::atomic<std::uint8_t>> marks_;
};

}  // namespace

LevelSet rebuildLevelSet(const TriDexelStock& stock, const RebuildOptions& options) {
    if (options.halfWidth < 3)
        throw Error("level set rebuild: half-width " + std::to_string(options.halfWidth) +
                    " voxels is below the minimum of 3");
    ensureOpenVdbInitialized();
    Rebuilder rebuilder(stock, options);
    openvdb::FloatGrid::Ptr grid = rebuilder.run();

    const Lattice& lat = stock.lattice();
    auto xform = openvdb::math::Transform::createLinearTransform(lat.h);
    const std::array<int, 3> off = rebuilder.offset();
    xform->postTranslate(openvdb::Vec3d(lat.origin.x + (0.5 - off[0]) * lat.h, lat.origin.y + (0.5 - off[1]) * lat.h,
                                        lat.origin.z + (0.5 - off[2]) * lat.h));
    grid->setTransform(xform);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->setName(detail::kGridName);
    detail::writeMeta(*grid, lat, options.source);

    auto impl = std::make_shared<LevelSet::Impl>();
    impl->grid = std::move(grid);
    return LevelSet(std::move(impl));
}

}  // namespace dexelmill
