// The linear nodes of a turning sweep's search (turning.cpp, notes h and i): which moves take
// them and how each part is cut into bands, the fixed-axis sweep of each node, and the cache that
// keeps the nodes every query shares.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <memory>
#include <optional>
#include <vector>

#include "dexelmill/sweep/turning.h"
#include "dexelmill/tool/offset.h"
#include "turning_levels.h"

namespace dexelmill {

using turning::heapLevel;
using turning::kMaxLevel;
using turning::kMaxLinearLevel;

namespace {

/// The deepest level whose linear nodes are kept (NodeCache): a part keeps at most
/// 2^(kMaxKeptLevel + 1) nodes, in a table per level (2^k slots at level k, 512 kB at level 16)
/// made when a query first needs a node of it. Deeper nodes are made by each query that needs
/// them and dropped, as few lines share a node that deep (on boat-xyzac at h = 0.5 mm, about 2
/// queries a node at level 13 and 1 at level 14). On the 10 degree rows of BM_TurningQuery,
/// whose leaves lie at level 16, keeping levels down to 14 only was 1.3 times slower.
constexpr int kMaxKeptLevel = 16;

/// How many levels above the static search's closing level (note c) the linear nodes' leaves
/// must lie for a move to take them. A node costs a one-part MoveSweep, about 1 us to make and
/// 2 kB to keep, against a static pose's solve. Before note j's anchored nodes the linear search
/// walked down to its leaves near every graze, and paid only 2 levels up (3 with a ball end swept
/// as capsules; docs/turning-search-history.md, change (h)). With them it stops about where
/// C w^2 reaches epsilon, and pays wherever its leaves lie no deeper than the closing level. Cut
/// time at h = 0.5 mm, one thread, this rule against 2 and 3 levels: boat-xyzac 1.57 s against 2.6 s,
/// boat-xyzbc 3.0 s against 4.6 s, the impeller (ball end) 16.1 s against 16.3 s; taking linear
/// nodes also where their leaves lie 3 or 8 levels deeper gained nothing more.
constexpr int kLinearLevelsSaved = 0;

/// The linear-node search cuts each part into bands of heights (note i) no taller than this many
/// times the part's largest radius, and into at most kMaxBands.
constexpr double kBandHeight = 1.0;
constexpr int kMaxBands = 8;
/// How far (mm) a band's bounds, grown by epsilon, keep off the joints of its part's pieces, so
/// that no piece is cut to a sliver.
constexpr double kBandJointGap = 1e-3;
/// A part is cut into bands only where their leaves lie at least this many levels above the whole
/// part's.
constexpr int kBandLevelsSaved = 2;
/// And only where note j's anchored nodes settle nodes from this level down or deeper. From the
/// level k where 4^-k omega |f| (the least C) reaches epsilon they settle the nodes near a graze,
/// whatever a band's first-order reach; above it the bands' smaller reach settles nodes sooner, at
/// the cost of a search per band. Moves as short as real programs' reach that level at
/// about 3; BM_TurningQuery's 32 mm moves at 7 (1 degree) and 8 (10 degrees). Measured, ns per
/// line, bands always against bands from this level: BM_TurningShortQuery at 0.6 degrees flat
/// 722 against 614 and bull nose 1,575 against 1,076; BM_TurningQuery at 1 degree flat 2,618
/// against 2,426 (never cut: 2,986); cut time of the impeller at h = 0.5 mm, one thread, 18.1 s
/// against 15.0 s.
constexpr int kBandAnchorLevel = 5;

/// A node above the leaves sweeps its band's tori (a bull nose's corner, grown by g) as chains of
/// tangent cones that lie at most kChainSlack g outside them, where at most kMaxChainCones do
/// (mitredOffsetChain); nearer the leaves, where more would be needed, the tori themselves. A
/// torus's sweep solves its grazing curve on each line (torusCrossings, half the bull nose's time
/// on BM_TurningQuery), the cones' sweeps are closed forms, and the looser grown band settles a
/// few nodes fewer. Measured, ns per line of the bull nose, against tori: BM_TurningQuery at
/// 1, 10 and 30 degrees 0.76-0.78, BM_TurningShortQuery 0.94; slack 2 g or 8 g, or at most 6 or
/// 24 cones, gained 1-5 % less. The nodes of BM_TurningQuery's bull nose at 30 degrees keep
/// 3.7 kB each instead of 2.4.
constexpr double kChainSlack = 4.0;
constexpr int kMaxChainCones = 12;

/// The linear nodes kept by every sweep alive, and how many they may keep.
std::atomic<std::size_t> keptNodes{0};
std::atomic<std::size_t> nodeBudget{kDefaultLinearNodeBudget};

/// The largest radius a profile piece reaches, or more.
double pieceRadiusBound(const ProfilePiece& piece) {
    if (const auto* c = std::get_if<ConePiece>(&piece)) return std::max(c->r0, c->r1);
    const ArcPiece& a = std::get<ArcPiece>(piece);
    return a.rc + a.rho;
}


/// The largest radius the pieces [first, last) reach, or more.
template <class It>
double radiusBound(It first, It last) {
    double radius = 0.0;
    for (It i = first; i != last; ++i) radius = std::max(radius, pieceRadiusBound(*i));
    return radius;
}

/// Note h's reach delta of a node of width w, for a band of half-height `half` and largest radius
/// `radius` about its pivot: omega (w / 2) hypot(half, radius) + K w^2 / 8, K the pivot's bend.
double nodeReach(double omega, double bend, double half, double radius, double w) {
    return 0.5 * omega * std::hypot(half, radius) * w + 0.125 * bend * w * w;
}

/// The fixed-axis move of a node (note h): the pivot, `pivot` up the axis, on the chord between
/// its places at the node's end poses a and b, the axis held at the middle pose's.
MoveSweep chordSweep(const std::vector<ProfilePiece>& pieces, double pivot, const ToolPose& a, const ToolPose& b,
                     const ToolPose& middle) {
    return MoveSweep(pieces, a.tip + pivot * (a.axis - middle.axis), b.tip + pivot * (b.axis - middle.axis),
                     middle.axis);
}

}  // namespace

/// The linear nodes made so far, per part by heap index: each made at most once, by whichever
/// query needs it first (one that loses the race to publish its node drops it), and read by
/// every query after. A level's table of slots is made the same way, by the first query that
/// needs one of its nodes: most moves touch a few nodes of a few levels, and a table made whole
/// with the sweep (up to 1 MiB a band, zeroed, then scanned to free it) cost boat-xyzac 2.5 % of
/// its instructions.
class TurningSweep::NodeCache {
    using Slot = std::atomic<const LinearNode*>;

  public:
    explicit NodeCache(const std::vector<LinearPart>& parts) : levels_(parts.size()) {
        for (const LinearPart& p : parts) keptLevels_.push_back(std::min(p.leafLevel(), kMaxKeptLevel));
        for (auto& part : levels_)
            for (auto& table : part) table.store(nullptr, std::memory_order_relaxed);
    }
    ~NodeCache() {
        for (auto& part : levels_)
            for (int k = 0; k <= kMaxKeptLevel; ++k) {
                Slot* table = part[std::size_t(k)].load(std::memory_order_relaxed);
                if (!table) continue;
                for (std::size_t i = 0; i < (std::size_t(1) << k); ++i) delete table[i].load(std::memory_order_relaxed);
                delete[] table;
            }
        keptNodes.fetch_sub(kept_.load(std::memory_order_relaxed), std::memory_order_relaxed);
    }
    NodeCache(const NodeCache&) = delete;
    NodeCache& operator=(const NodeCache&) = delete;

    /// The node, kept; or, when it lies deeper than kMaxKeptLevel or the sweeps alive keep their
    /// budget already, made in `scratch`.
    template <class Make>
    const LinearNode& get(std::size_t part, std::uint32_t heap, std::unique_ptr<LinearNode>& scratch, Make&& make) {
        const int level = heapLevel(heap);
        if (level > keptLevels_[part]) return *(scratch = std::make_unique<LinearNode>(make()));
        Slot& slot = table(part, level)[heap - (std::uint32_t(1) << level)];
        if (const LinearNode* n = slot.load(std::memory_order_acquire)) return *n;
        if (keptNodes.fetch_add(1, std::memory_order_relaxed) >= nodeBudget.load(std::memory_order_relaxed)) {
            keptNodes.fetch_sub(1, std::memory_order_relaxed);
            return *(scratch = std::make_unique<LinearNode>(make()));
        }
        kept_.fetch_add(1, std::memory_order_relaxed);
        auto made = std::make_unique<const LinearNode>(make());
        const LinearNode* seen = nullptr;
        if (slot.compare_exchange_strong(seen, made.get(), std::memory_order_acq_rel, std::memory_order_acquire))
            return *made.release();
        kept_.fetch_sub(1, std::memory_order_relaxed);
        keptNodes.fetch_sub(1, std::memory_order_relaxed);
        return *seen;
    }

  private:
    /// Level k's slots of part `part`, made (zeroed) and published by the first query to need them.
    Slot* table(std::size_t part, int k) {
        std::atomic<Slot*>& entry = levels_[part][std::size_t(k)];
        if (Slot* t = entry.load(std::memory_order_acquire)) return t;
        std::unique_ptr<Slot[]> made(new Slot[std::size_t(1) << k]());
        Slot* seen = nullptr;
        if (entry.compare_exchange_strong(seen, made.get(), std::memory_order_acq_rel, std::memory_order_acquire))
            return made.release();
        return seen;
    }

    std::vector<std::array<std::atomic<Slot*>, kMaxKeptLevel + 1>> levels_;
    std::vector<int> keptLevels_;  ///< per part, the deepest level it keeps
    std::atomic<std::size_t> kept_{0};
};

std::size_t TurningSweep::keptLinearNodes() { return keptNodes.load(std::memory_order_relaxed); }

void TurningSweep::setLinearNodeBudget(std::size_t nodes) { nodeBudget.store(nodes, std::memory_order_relaxed); }

std::size_t TurningSweep::linearNodeBudget() { return nodeBudget.load(std::memory_order_relaxed); }

std::size_t TurningSweep::linearNodeBound() const {
    std::size_t nodes = 0;
    for (const LinearPart& m : models_) nodes += (std::size_t(2) << std::min(m.leafLevel(), kMaxKeptLevel)) - 1;
    return nodes;
}

const TurningSweep::LinearNode& TurningSweep::linearNode(std::size_t band, std::uint32_t heap,
                                                          std::unique_ptr<LinearNode>& scratch) const {
    return nodes_->get(band, heap, scratch, [&] { return makeNode(models_[band], heap); });
}

TurningSweep::LinearNode TurningSweep::makeNode(const LinearPart& m, std::uint32_t heap) const {
    const int level = heapLevel(heap);
    const double width = turning::heapWidth(heap);
    const double ua = double(heap - (std::uint32_t(1) << level)) * width, ub = ua + width, um = ua + 0.5 * width;
    const TurnPhase middle = law_.phase(um);
    const ToolPose a = law_.pose(ua), b = law_.pose(ub), mid = law_.pose(middle);
    // Above the leaves, the band grown by the reach less epsilon (more than 0 there); a leaf
    // sweeps the band itself.
    if (level == m.leafLevel()) return LinearNode{chordSweep(m.band, m.pivot, a, b, mid), mid, um, width, middle};
    const double g = m.reach[std::size_t(level)] - epsilon_;
    const std::vector<ProfilePiece> grown = mitredOffsetChain(m.band, g, kChainSlack * g, kMaxChainCones);
    return LinearNode{chordSweep(grown, m.pivot, a, b, mid), mid, um, width, middle};
}

std::optional<TurningSweep::LinearPart> TurningSweep::linearBand(std::size_t p, double lo, double hi, int deepest) const {
    const ConvexPart& part = parts_[p];
    LinearPart m;
    m.part = p;
    std::vector<ProfilePiece> band = clipChain(tool_.pieces(), part.first, part.last, lo, hi);
    const double radius = radiusBound(band.begin(), band.end());
    m.pivot = 0.5 * (lo + hi);
    m.lo = lo;
    m.hi = hi;
    const double bend = law_.axisPointAccelerationBound(m.pivot);
    for (int k = 0;; ++k) {
        m.reach.push_back(nodeReach(axisTurn_, bend, 0.5 * (hi - lo), radius, std::ldexp(1.0, -k)));
        if (m.reach.back() <= epsilon_) break;
        if (k >= deepest) return std::nullopt;
    }
    m.band = std::move(band);
    return m;
}

void TurningSweep::chooseLinearNodes() {
    const int deepest = std::min(kMaxLinearLevel, closingLevel_ - kLinearLevelsSaved);
    int anchorLevel = 0;
    const double leastBend = axisTurn_ * law_.speedBound(0.0);
    while (anchorLevel < kMaxLevel && std::ldexp(leastBend, -2 * anchorLevel) > epsilon_) ++anchorLevel;
    const auto& pieces = tool_.pieces();
    std::vector<LinearPart> models;
    std::vector<std::optional<LinearNode>> wholeRoots(parts_.size());
    for (std::size_t p = 0; p < parts_.size(); ++p) {
        const ConvexPart& part = parts_[p];
        const double radius = radiusBound(pieces.begin() + std::ptrdiff_t(part.first),
                                          pieces.begin() + std::ptrdiff_t(part.last));
        // Bands of equal height (note i), their bounds grown by epsilon kept off the part's
        // joints.
        const double height = part.z1 - part.z0, apart = 2.0 * (epsilon_ + kBandJointGap);
        const int count = int(std::clamp(std::ceil(height / (kBandHeight * radius)), 1.0, double(kMaxBands)));
        std::vector<double> bounds{part.z0};
        for (int b = 1; b < count; ++b) {
            double z = part.z0 + height * b / count;
            for (std::size_t i = part.first + 1; i < part.last; ++i)
                if (std::abs(z - pieceZ0(pieces[i])) < 0.5 * apart) z = pieceZ0(pieces[i]) + apart;
            if (z - bounds.back() > apart && part.z1 - z > apart) bounds.push_back(z);
        }
        bounds.push_back(part.z1);
        std::vector<LinearPart> bands;
        int bandLeaf = 0;
        // Bands only where the anchored nodes leave them levels to save (they are made for
        // nothing otherwise: five a flat D10 x 25).
        for (std::size_t b = 0; anchorLevel >= kBandAnchorLevel && b + 1 < bounds.size(); ++b) {
            const double lo = b == 0 ? part.z0 : bounds[b] - epsilon_;
            const double hi = b + 2 == bounds.size() ? part.z1 : bounds[b + 1] + epsilon_;
            std::optional<LinearPart> band = linearBand(p, lo, hi, deepest);
            if (!band) break;
            bandLeaf = std::max(bandLeaf, band->leafLevel());
            bands.push_back(std::move(*band));
        }
        // The whole part; with bands, made down to its own leaves if need be, as its root settles
        // every band of a line far from the part.
        const bool banded =
            bands.size() + 1 == bounds.size() && bands.size() > 1 && anchorLevel >= kBandAnchorLevel;
        std::optional<LinearPart> whole = linearBand(p, part.z0, part.z1, banded ? kMaxLevel : deepest);
        const bool wholeFits = whole && whole->leafLevel() <= deepest;
        if (banded && (!wholeFits || whole->leafLevel() >= bandLeaf + kBandLevelsSaved)) {
            if (whole && whole->leafLevel() > 0) wholeRoots[p].emplace(makeNode(*whole, 1));
            for (LinearPart& band : bands) models.push_back(std::move(band));
        } else if (wholeFits) {
            models.push_back(std::move(*whole));
        } else {
            return;
        }
    }
    models_ = std::move(models);
    wholeRoots_ = std::move(wholeRoots);
    nodes_ = std::make_shared<NodeCache>(models_);
    // Every output interval lies within epsilon of a pose (note e), and every pose of a part
    // within the root's reach delta_0 of the root's linear move (note h): so inside the part
    // grown by delta_0 + epsilon swept along that move, whose box in its frame bound() takes.
    // The tool's own parts, as a ball end's ball is inside the lowest.
    const ToolPose start = law_.pose(0.0), end = law_.pose(1.0), middle = law_.pose(0.5);
    for (const ConvexPart& part : tool_.convexParts()) {
        const std::vector<ProfilePiece> chain(pieces.begin() + std::ptrdiff_t(part.first),
                                              pieces.begin() + std::ptrdiff_t(part.last));
        const double pivot = 0.5 * (part.z0 + part.z1);
        const double reach = nodeReach(axisTurn_, law_.axisPointAccelerationBound(pivot), 0.5 * (part.z1 - part.z0),
                                       radiusBound(chain.begin(), chain.end()), 1.0);
        outer_.push_back(chordSweep(mitredOffsetChain(chain, reach + epsilon_), pivot, start, end, middle));
    }
}

}  // namespace dexelmill
