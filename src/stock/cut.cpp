#include "dexelmill/stock/cut.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"
#include "dexelmill/path/motion.h"
#include "dexelmill/sweep/sweep.h"

namespace dexelmill {

namespace {

constexpr int kTile = DexelTile::kTile;

/// One tile of one family, with the extent of its material along the family's axis (relative
/// to the lattice origin; empty when lo > hi). The extent only shrinks while cutting.
struct TileSlot {
    int family = 0, tb = 0, tc = 0;
    float lo = std::numeric_limits<float>::infinity();
    float hi = -std::numeric_limits<float>::infinity();
};

/// A tile's contribution to one move's statistics; lengths in mm summed over the tile's dexels.
struct TileMoveStats {
    std::uint32_t move = 0;  ///< index within the batch
    std::uint32_t bounded = 0, visited = 0, changed = 0;
    double removed = 0.0, shank = 0.0, holder = 0.0, design = 0.0;
};

/// What a tile needs to watch the design: its dexels' design material, the depth below which
/// a stretch is not kept, and the length at or below which it is not kept either (`sliver`).
struct DesignWatch {
    const DexelTile* tile = nullptr;
    double depth = 0.0;
    /// Twice the ends' rounding (endRounding, L 2^-23 for a lattice whose longest side is L mm):
    /// a stretch whose true ends coincide is stored at most this long. So is what a move removes
    /// along a line its sweep only touches. The tool's side tangent to a dexel meets it in a point,
    /// which double arithmetic makes a chord of about sqrt(r L) 2^-25 mm for a tool of radius r
    /// (r^2 - d^2 off by a few r L 2^-53), at most L 2^-23 for any r up to 16 L, and float storage
    /// adds at most that again; a move retracing an earlier one's surface stores the same end or
    /// the next float. Such a stretch removes no design material, and a move is named for the
    /// material it removes.
    double sliver = 0.0;
    /// The dexels' length, and whether the design runs on past their start and their end (the
    /// cast cut it off at the lattice's box there).
    float length = 0.0f;
    bool openLo = false, openHi = false;
};

/// The material of `segs` inside [lo, hi] that the design's segments keep: returns its length, and
/// appends to `out` (with only the dexel's [lo, hi] filled in) the pieces longer than
/// `watch.sliver` where the design's segment reaches farther than `watch.depth` beyond some point
/// of the piece on both sides. A design segment at an open end of the dexel (DesignWatch) reaches
/// without bound that way.
double designOverlap(const SegmentSpan& segs, const DesignWatch& watch, const SegmentSpan& design, float lo, float hi,
                     const DesignStretch& at, std::vector<DesignStretch>& out) {
    constexpr double kUnbounded = std::numeric_limits<double>::infinity();
    double sum = 0.0;
    for (const Segment& s : segs) {
        if (s.lo >= hi) break;
        if (s.hi <= lo) continue;
        const float x0 = std::max(s.lo, lo), x1 = std::min(s.hi, hi);
        for (const Segment& d : design) {
            if (d.lo >= x1) break;
            if (d.hi <= x0) continue;
            const float p = std::max(x0, d.lo), q = std::min(x1, d.hi);
            sum += double(q) - double(p);
            const double dlo = watch.openLo && d.lo <= 0.0f ? -kUnbounded : double(d.lo);
            const double dhi = watch.openHi && d.hi >= watch.length ? kUnbounded : double(d.hi);
            // How far d reaches on both sides of the point of [p, q] farthest inside it along the
            // line: d's midpoint, clamped; p or q when d runs on one way; anywhere when both.
            double reach = kUnbounded;
            if (std::isfinite(dlo) && std::isfinite(dhi)) {
                const double t = std::clamp(0.5 * (dlo + dhi), double(p), double(q));
                reach = std::min(t - dlo, dhi - t);
            } else if (std::isfinite(dhi)) {
                reach = dhi - double(p);
            } else if (std::isfinite(dlo)) {
                reach = double(q) - dlo;
            }
            if (reach > watch.depth && double(q) - double(p) > watch.sliver) {
                DesignStretch piece = at;
                piece.lo = p;
                piece.hi = q;
                piece.reach = reach;
                out.push_back(piece);
            }
        }
    }
    return sum;
}

void updateExtent(const DexelTile& tile, TileSlot& slot) {
    slot.lo = std::numeric_limits<float>::infinity();
    slot.hi = -std::numeric_limits<float>::infinity();
    if (tile.empty()) return;
    for (int i = 0; i < DexelTile::kDexels; ++i) {
        const SegmentSpan s = tile.segments(i);
        if (s.empty()) continue;
        slot.lo = std::min(slot.lo, s[0].lo);
        slot.hi = std::max(slot.hi, s[s.size - 1].hi);
    }
}

/// Length of material of a dexel inside [lo, hi].
double overlapLength(const SegmentSpan& segs, float lo, float hi) {
    double sum = 0.0;
    for (const Segment& s : segs) {
        if (s.lo >= hi) break;
        if (s.hi > lo) sum += double(std::min(s.hi, hi)) - double(std::max(s.lo, lo));
    }
    return sum;
}

/// Length of material of a dexel inside the union of `ranges` (as dexel endpoints), which may
/// overlap: sorted and merged in place first, so that none is counted twice.
double unionOverlapLength(const SegmentSpan& segs, std::vector<std::pair<float, float>>& ranges) {
    std::sort(ranges.begin(), ranges.end());
    double sum = 0.0;
    for (std::size_t i = 0; i < ranges.size();) {
        float lo = ranges[i].first, hi = ranges[i].second;
        for (++i; i < ranges.size() && ranges[i].first <= hi; ++i) hi = std::max(hi, ranges[i].second);
        sum += overlapLength(segs, lo, hi);
    }
    return sum;
}

/// A line parameter as a dexel endpoint (float), kept finite.
float toFloat(double v) {
    constexpr double big = 1e30;
    return float(std::clamp(v, -big, big));
}

/// Whether subtracting any interval inside `reach` could change the dexel: some segment overlaps
/// reach's float ends the way DexelTile::subtract tests overlap. Float rounding is monotone, so an
/// interval inside reach rounds to one inside these ends.
bool reachesMaterial(const SegmentSpan& segs, const Interval& reach) {
    if (reach.isEmpty()) return false;
    const float lo = toFloat(reach.lo), hi = toFloat(reach.hi);
    for (const Segment& s : segs) {
        if (s.lo >= hi) return false;
        if (s.hi > lo) return true;
    }
    return false;
}

/// Whether a dexel parameter lies strictly inside one of the segments: where a subtraction ending
/// there makes a new segment end (DexelTile::subtract's test).
bool insideMaterial(const SegmentSpan& segs, float x) {
    for (const Segment& s : segs) {
        if (s.lo >= x) return false;
        if (s.hi > x) return true;
    }
    return false;
}

/// Removes a swept interval from a dexel. The material left at a new end faces the cutter: its
/// outward normal is the sweep's, reversed.
double subtractHit(DexelTile& tile, int local, const LineHit& hit) {
    return tile.subtract(local, toFloat(hit.range.lo), toFloat(hit.range.hi), -hit.normalLo, hit.sharpLo,
                         -hit.normalHi, hit.sharpHi);
}

/// Where one sweep can reach in a tile: the dexels its box crosses, and its extent along them
/// (relative to the lattice origin).
struct SweepWindow {
    int b0 = 0, b1 = -1, c0 = 0, c1 = -1;
    double lo = 0.0, hi = -1.0;

    SweepWindow() = default;
    SweepWindow(const Lattice& lattice, Axis axB, Axis axC, int ia, double originA, const Box& box) {
        const auto rb = lattice.indexRange(axB, box.lo[index(axB)], box.hi[index(axB)]);
        const auto rc = lattice.indexRange(axC, box.lo[index(axC)], box.hi[index(axC)]);
        b0 = rb[0], b1 = rb[1], c0 = rc[0], c1 = rc[1];
        lo = box.lo[ia] - originA, hi = box.hi[ia] - originA;
    }
    /// Whether the box crosses dexel (ib, ic) where it has material (segs non-empty).
    bool meets(int ib, int ic, const SegmentSpan& segs) const {
        return ib >= b0 && ib <= b1 && ic >= c0 && ic <= c1 && double(segs[0].lo) <= hi &&
               double(segs[segs.size - 1].hi) >= lo;
    }
};

/// Applies the sweeps `moves` (indices into the batch's, MovePieces) to one tile, in order.
void processTile(TriDexelStock& stock, TileSlot& slot, const BuiltSweeps& geoms,
                 const std::vector<std::uint32_t>& moves, bool removeShank, const DesignWatch& design,
                 std::vector<TileMoveStats>& out, std::vector<DesignStretch>& stretches) {
    const Lattice& lattice = stock.lattice();
    const Axis a = axisFromIndex(slot.family);
    DexelFamily& fam = stock.family(a);
    DexelTile& tile = fam.tile(slot.tb, slot.tc);
    const Axis axB = fam.axisB(), axC = fam.axisC();
    const int ia = index(a), ibx = index(axB), icx = index(axC);
    const int ib0 = slot.tb * kTile, ic0 = slot.tc * kTile;
    const int ib1 = std::min(ib0 + kTile, fam.nb()) - 1, ic1 = std::min(ic0 + kTile, fam.nc()) - 1;
    const double originA = lattice.origin[ia];

    Line line;
    line.dir = axisVector(a);
    line.origin[ia] = originA;
    LineHit parts[MoveSweep::kMaxParts];
    std::vector<Interval> material;  // a dexel's segments, for a turning sweep's care
    std::vector<LineHit> turned;     // a turning sweep's intervals along a dexel
    std::vector<std::pair<float, float>> met;  // the shank's intervals, where it does not subtract
    // For the sweeps that only measure: no interval end becomes a segment end.
    const MoveSweep::EndFilter noEnds = [](std::size_t, const Interval&) { return 0u; };

    for (std::uint32_t m : moves) {
        if (slot.lo > slot.hi) break;  // no material left in the tile
        const MoveGeometry& g = geoms[m];
        // The box along the dexels, relative to the lattice origin, against the tile's material.
        const double boxLo = g.box.lo[ia] - originA, boxHi = g.box.hi[ia] - originA;
        if (boxHi < double(slot.lo) || boxLo > double(slot.hi)) continue;
        const auto rb = lattice.indexRange(axB, g.box.lo[ibx], g.box.hi[ibx]);
        const auto rc = lattice.indexRange(axC, g.box.lo[icx], g.box.hi[icx]);
        const int b0 = std::max(rb[0], ib0), b1 = std::min(rb[1], ib1);
        const int c0 = std::max(rc[0], ic0), c1 = std::min(rc[1], ic1);
        if (b0 > b1 || c0 > c1) continue;

        // The cutting part and the shank each bounded only where their own boxes reach: the shank
        // mostly runs above the stock.
        const SweepWindow cutWin =
            g.cutting ? SweepWindow(lattice, axB, axC, ia, originA, g.cutting.bounds()) : SweepWindow();
        const SweepWindow shankWin =
            g.shank ? SweepWindow(lattice, axB, axC, ia, originA, g.shank.bounds()) : SweepWindow();
        const SweepWindow holderWin =
            g.holder ? SweepWindow(lattice, axB, axC, ia, originA, g.holder.bounds()) : SweepWindow();
        TileMoveStats st;
        st.move = m;
        for (int ic = c0; ic <= c1; ++ic) {
            line.origin[icx] = lattice.coord(axC, ic);
            for (int ib = b0; ib <= b1; ++ib) {
                const int local = (ib - ib0) + kTile * (ic - ic0);
                const SegmentSpan segs = tile.segments(local);
                if (segs.empty() || double(segs[0].lo) > boxHi || double(segs[segs.size - 1].hi) < boxLo)
                    continue;
                line.origin[ibx] = lattice.coord(axB, ib);
                ++st.bounded;
                // Per dexel: a cheap bound of the sweep along this line against its material
                // (most dexels under a finishing pass were cut down by the moves before).
                const bool cuts = g.cutting && cutWin.meets(ib, ic, segs);
                const bool shank = g.shank && shankWin.meets(ib, ic, segs);
                const bool holder = shank && g.holder && holderWin.meets(ib, ic, segs);
                const Interval cutReach = cuts ? g.cutting.bound(line) : Interval::empty();
                const Interval shankReach = shank ? g.shank.bound(line) : Interval::empty();
                const Interval holderReach = holder ? g.holder.bound(line) : Interval::empty();
                if (!reachesMaterial(segs, cutReach.hull(shankReach))) continue;
                // A fixed-axis sweep's line in its frame, for its hits: made only here, as the
                // bounds take the boxes in world coordinates and reject most lines of the window.
                const MoveSweep::LocalLine cutLine =
                    cuts && g.cutting.fixed ? g.cutting.fixed->toLocal(line) : MoveSweep::LocalLine{};
                const MoveSweep::LocalLine shankLine =
                    shank && g.shank.fixed ? g.shank.fixed->toLocal(line) : MoveSweep::LocalLine{};
                const MoveSweep::LocalLine holderLine =
                    holder && g.holder.fixed ? g.holder.fixed->toLocal(line) : MoveSweep::LocalLine{};
                ++st.visited;
                // The share of a cell's cross-section this dexel stands for (Lattice::share).
                const double share = lattice.dexelShare(a, ib, ic);
                double removed = 0.0;
                // The Hermite data only for the interval ends that will become segment ends: those
                // inside material. (A part's subtraction only removes material, so the ends flagged
                // before it are a superset of those the next part makes.)
                const MoveSweep::EndFilter makesEnds = [&](std::size_t, const Interval& range) {
                    const SegmentSpan now = tile.segments(local);
                    return (insideMaterial(now, toFloat(range.lo)) ? MoveSweep::kEndLo : 0u) |
                           (insideMaterial(now, toFloat(range.hi)) ? MoveSweep::kEndHi : 0u);
                };
                // Before a removal: the design's material it takes.
                auto watch = [&](const LineHit& hit) {
                    if (!design.tile) return;
                    const SegmentSpan kept = design.tile->segments(local);
                    if (kept.empty()) return;
                    DesignStretch at;
                    at.move = m, at.family = a, at.ib = ib, at.ic = ic;
                    st.design += share * designOverlap(tile.segments(local), design, kept, toFloat(hit.range.lo),
                                                       toFloat(hit.range.hi), at, stretches);
                };
                // Applies `apply` to the swept intervals of one region: a fixed-axis sweep's parts,
                // or a turning sweep's intervals, solved to its tolerance where the dexel has
                // material within the sweep's bound `reach`.
                // A fixed-axis sweep makes the Hermite data of the ends `ends` asks for.
                auto forEachHit = [&](const RegionSweep& sweep, const MoveSweep::LocalLine& frameLine,
                                      const Interval& reach, const MoveSweep::EndFilter& ends, auto&& apply) {
                    if (sweep.fixed) {
                        const std::size_t n = sweep.fixed->intersectParts(frameLine, parts, ends);
                        for (std::size_t k = 0; k < n; ++k)
                            if (!parts[k].isEmpty()) apply(parts[k]);
                        return;
                    }
                    material.clear();
                    for (const Segment& sg : tile.segments(local)) {
                        const Interval met = Interval{double(sg.lo), double(sg.hi)}.intersect(reach);
                        if (!met.isEmpty()) material.push_back(met);
                    }
                    if (material.empty()) return;
                    sweep.turning->intersect(line, material, turned);
                    for (const LineHit& hit : turned) apply(hit);
                };
                if (cuts) {
                    forEachHit(g.cutting, cutLine, cutReach, makesEnds, [&](const LineHit& hit) {
                        watch(hit);
                        removed += subtractHit(tile, local, hit);
                    });
                }
                // The holder's share of what the shank region meets, measured on the material it
                // is about to meet: the holder is one cylinder, whose sweep's intervals along a
                // line do not overlap (one part, or a turning sweep's union), so none is counted
                // twice.
                if (holder) {
                    forEachHit(g.holder, holderLine, holderReach, noEnds, [&](const LineHit& hit) {
                        st.holder += share * overlapLength(tile.segments(local), toFloat(hit.range.lo),
                                                           toFloat(hit.range.hi));
                    });
                }
                if (shank) {
                    // Its parts' intervals overlap where the move runs along their axis, or where
                    // the dexel lies on a face two parts share: without subtracting, what they
                    // meet is measured on their union.
                    met.clear();
                    const MoveSweep::EndFilter& shankEnds = removeShank ? makesEnds : noEnds;
                    forEachHit(g.shank, shankLine, shankReach, shankEnds, [&](const LineHit& hit) {
                        if (removeShank) {
                            watch(hit);
                            const double length = subtractHit(tile, local, hit);
                            st.shank += share * length;
                            removed += length;
                        } else {
                            met.emplace_back(toFloat(hit.range.lo), toFloat(hit.range.hi));
                        }
                    });
                    if (!met.empty()) st.shank += share * unionOverlapLength(tile.segments(local), met);
                }
                if (removed > 0.0) {
                    ++st.changed;
                    st.removed += share * removed;
                }
            }
        }
        if (st.changed > 0) updateExtent(tile, slot);
        if (st.bounded > 0) out.push_back(st);
    }
}

}  // namespace

std::map<int, ToolRegions> toolRegions(const ToolPath& path, const ToolTable& tools) {
    std::map<int, ToolRegions> regions;
    for (std::size_t i = 0; i < path.moves.size(); ++i) {
        const Move& mv = path.moves[i];
        if (regions.count(mv.tool)) continue;
        const auto it = tools.find(mv.tool);
        if (it == tools.end())
            throw Error(path.where(mv.source).str() + ": move " + std::to_string(ToolPath::moveNumber(i)) + " uses tool T" +
                        std::to_string(mv.tool) + ", which is not in the tool table");
        const Tool& t = it->second;
        ToolRegions r;
        const bool hasShank = t.cuttingLength() < t.totalLength() - tol::kLength;
        r.cutting.emplace(hasShank ? t.region(t.bottom(), t.cuttingLength()) : t);
        if (hasShank) r.shank.emplace(t.region(t.cuttingLength(), t.totalLength()));
        // withHolder puts the holder at the stick-out's top, at or above the cutting length.
        if (t.hasHolder())
            r.holder.emplace(t.region(std::max(t.holderBottom(), t.cuttingLength()), t.totalLength()));
        if (r.cutting->convexParts().size() > MoveSweep::kMaxParts ||
            (r.shank && r.shank->convexParts().size() > MoveSweep::kMaxParts))
            throw Error("tool " + std::to_string(mv.tool) + " ('" + t.description() + "') has more than " +
                        std::to_string(MoveSweep::kMaxParts) + " convex parts");
        regions.emplace(mv.tool, std::move(r));
    }
    return regions;
}

bool sweepsTurning(const Move& move, const Tool& tool, double turnTolerance) {
    const double reach = std::hypot(tool.totalLength(), tool.maxRadius());
    if (move.rotary) return MotionLaw(move).turnBound(reach) > turnTolerance;
    return move.turns() && !move.rapid && turnAngle(move) * reach > turnTolerance;
}

bool sweptTurning(const ToolRegions& regions, const Move& move, double turnTolerance) {
    return sweepsTurning(move, *regions.cutting, turnTolerance) ||
           (regions.shank && sweepsTurning(move, *regions.shank, turnTolerance));
}

MovePieces::MovePieces(const ToolPath& path, const std::map<int, ToolRegions>& regions, double turnTolerance)
    : path_(path), size_(path.moves.size()) {
    for (std::size_t i = 0; i < path.moves.size(); ++i) {
        const Move& m = path.moves[i];
        if (!m.turns() || !sweptTurning(regions.at(m.tool), m, turnTolerance)) continue;
        const double pieces = std::ceil(MotionLaw(m).rateSum() / kMaxPieceTurn - kPieceRounding);
        if (!(pieces > 1.0)) continue;
        const std::size_t count = std::size_t(pieces);
        const std::size_t sweeps = regions.at(m.tool).shank ? 2 * count : count;
        // The sweeps of the moves cut before add to this one's place.
        cuts_.push_back({i, i + (size_ - path.moves.size()), count, sweeps});
        size_ += sweeps - 1;
    }
}

const MovePieces::Cut* MovePieces::before(std::size_t i) const {
    const auto after = std::upper_bound(cuts_.begin(), cuts_.end(), i,
                                        [](std::size_t piece, const Cut& c) { return piece < c.first; });
    return after == cuts_.begin() ? nullptr : &*(after - 1);
}

std::size_t MovePieces::move(std::size_t i) const {
    const Cut* c = before(i);
    if (!c) return i;
    return i < c->first + c->sweeps ? c->move : c->move + 1 + (i - (c->first + c->sweeps));
}

Move MovePieces::piece(std::size_t i) const {
    const Cut* c = before(i);
    if (!c || i >= c->first + c->sweeps) return path_.moves[move(i)];
    const double n = double(c->count), k = double((i - c->first) % c->count);
    return subMove(path_.moves[c->move], k / n, (k + 1.0) / n);
}

Regions MovePieces::regions(std::size_t i) const {
    const Cut* c = before(i);
    if (!c || i >= c->first + c->sweeps) return Regions::Both;
    return i - c->first < c->count ? Regions::Cutting : Regions::Shank;
}

MoveGeometry::MoveGeometry(const ToolRegions& regions, const Move& move, double turnTolerance, Regions which) {
    const bool turning = sweptTurning(regions, move, turnTolerance);
    auto sweep = [&](const Tool& region, RegionSweep& out) {
        if (turning) out.turning.emplace(region, move, turnTolerance);
        else out.fixed.emplace(region, move);
        box.expand(out.bounds());
    };
    if (which != Regions::Shank) sweep(*regions.cutting, cutting);
    if (regions.shank && which != Regions::Cutting) sweep(*regions.shank, shank);
    if (regions.holder && which != Regions::Cutting) sweep(*regions.holder, holder);
}

std::size_t MoveGeometry::linearNodeBound() const {
    std::size_t nodes = 0;
    for (const RegionSweep* r : {&cutting, &shank, &holder})
        if (r->turning) nodes += r->turning->linearNodeBound();
    return nodes;
}

std::size_t movesWithinNodeBudget(const BuiltSweeps& geoms, std::size_t count) {
    const std::size_t budget = TurningSweep::linearNodeBudget();
    std::size_t nodes = geoms[0].linearNodeBound(), n = 1;
    for (; n < count; ++n) {
        nodes += geoms[n].linearNodeBound();
        if (nodes > budget) break;
    }
    return n;
}

CutResult cutStock(TriDexelStock& stock, const ToolPath& path, const ToolTable& tools, const CutOptions& options) {
    const std::size_t nMoves = path.moves.size();
    CutResult result;
    result.moves.resize(nMoves);

    const std::map<int, ToolRegions> regions = toolRegions(path, tools);
    const MovePieces pieces(path, regions, options.turnTolerance);
    const std::size_t nPieces = pieces.size();

    // Every tile of every kept family, with its material extent.
    std::vector<TileSlot> slots;
    std::size_t familyBase[3] = {0, 0, 0};
    int familyCount = 0;
    for (int a = 0; a < 3; ++a) {
        familyBase[a] = slots.size();
        if (!stock.has(axisFromIndex(a))) continue;
        ++familyCount;
        const DexelFamily& fam = stock.family(axisFromIndex(a));
        for (int tc = 0; tc < fam.tilesC(); ++tc)
            for (int tb = 0; tb < fam.tilesB(); ++tb) slots.push_back(TileSlot{a, tb, tc});
    }

    tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
    arena.execute([&] {
        tbb::parallel_for(std::size_t(0), slots.size(), [&](std::size_t i) {
            TileSlot& s = slots[i];
            updateExtent(stock.family(axisFromIndex(s.family)).tile(s.tb, s.tc), s);
        });
    });

    const Lattice& lattice = stock.lattice();
    const double cell = lattice.h * lattice.h / std::max(1, familyCount);
    const std::size_t batch =
        options.batchMoves > 0 ? options.batchMoves : std::max<std::size_t>(64, (nPieces + 99) / 100);
    std::vector<std::vector<std::uint32_t>> tileMoves(slots.size());
    std::vector<std::vector<TileMoveStats>> tileStats(slots.size());
    std::vector<std::vector<DesignStretch>> tileStretches(slots.size());
    if (options.design) {
        const TriDexelStock& d = *options.design;
        if (d.lattice().n != lattice.n || d.lattice().h != lattice.h || d.lattice().origin != lattice.origin)
            throw Error("cutting: the design is not cast on the stock's lattice");
        for (int a = 0; a < 3; ++a)
            if (stock.has(axisFromIndex(a)) && !d.has(axisFromIndex(a)))
                throw Error("cutting: the design lacks the stock's " + std::string(1, "xyz"[a]) + " dexels");
    }
    auto watchOf = [&](const TileSlot& s) {
        DesignWatch w;
        if (options.design) {
            w.tile = &options.design->family(axisFromIndex(s.family)).tile(s.tb, s.tc);
            w.depth = options.designDepth;
            w.sliver = 2.0 * endRounding(lattice);
            const int a = s.family;
            const double len = lattice.n[std::size_t(a)] * lattice.h;
            w.length = float(len);
            const Box& b = options.designBounds;
            w.openLo = !b.isEmpty() && b.lo[a] < lattice.origin[a];
            w.openHi = !b.isEmpty() && b.hi[a] > lattice.origin[a] + len;
        }
        return w;
    };
    std::vector<std::size_t> active;
    BuiltSweeps geoms;
    std::vector<DesignStretch> batchStretches;

    // geoms[i - m0] is the sweep of piece i; the first `built` of them were built with the batch
    // before. A batch, a tile's list and its statistics count pieces (MovePieces), the reports moves.
    std::size_t built = 0;
    for (std::size_t m0 = 0, m1 = 0; m0 < nPieces; m0 = m1) {
        // The batch's sweeps, built once and shared read-only by the tiles.
        const std::size_t end = std::min(nPieces, m0 + batch);
        geoms.resize(end - m0);
        arena.execute([&] {
            tbb::parallel_for(m0 + built, end, [&](std::size_t i) {
                const Move piece = pieces.piece(i);
                geoms[i - m0] = MoveGeometry(regions.at(piece.tool), piece, options.turnTolerance, pieces.regions(i));
            });
        });
        // The batch ends before its turning sweeps could keep more linear nodes than the budget.
        m1 = m0 + movesWithinNodeBudget(geoms, end - m0);
        // Bucket the moves by the tiles their boxes overlap, in program order.
        active.clear();
        for (std::size_t i = m0; i < m1; ++i) {
            const Box& box = geoms[i - m0].box;
            for (int a = 0; a < 3; ++a) {
                if (!stock.has(axisFromIndex(a))) continue;
                const DexelFamily& fam = stock.family(axisFromIndex(a));
                const auto rb = lattice.indexRange(fam.axisB(), box.lo[index(fam.axisB())], box.hi[index(fam.axisB())]);
                const auto rc = lattice.indexRange(fam.axisC(), box.lo[index(fam.axisC())], box.hi[index(fam.axisC())]);
                if (rb[0] > rb[1] || rc[0] > rc[1]) continue;
                for (int tc = rc[0] / kTile; tc <= rc[1] / kTile; ++tc) {
                    for (int tb = rb[0] / kTile; tb <= rb[1] / kTile; ++tb) {
                        const std::size_t t = familyBase[a] + std::size_t(tb) + std::size_t(fam.tilesB()) * tc;
                        if (slots[t].lo > slots[t].hi) continue;  // no material
                        if (tileMoves[t].empty()) active.push_back(t);
                        tileMoves[t].push_back(std::uint32_t(i - m0));
                    }
                }
            }
        }
        std::sort(active.begin(), active.end());
        arena.execute([&] {
            tbb::parallel_for(std::size_t(0), active.size(), [&](std::size_t k) {
                const std::size_t t = active[k];
                processTile(stock, slots[t], geoms, tileMoves[t], options.removeShankMaterial, watchOf(slots[t]),
                            tileStats[t], tileStretches[t]);
            });
        });
        // Reduce in tile order: the same sums in the same order for any thread count.
        for (std::size_t t : active) {
            for (const TileMoveStats& s : tileStats[t]) {
                MoveStats& ms = result.moves[pieces.move(m0 + s.move)];
                ms.bounded += s.bounded;
                ms.visited += s.visited;
                ms.changed += s.changed;
                ms.removed += s.removed * cell;
                ms.shankVolume += s.shank * cell;
                ms.holderVolume += s.holder * cell;
                ms.designRemoved[std::size_t(slots[t].family)] += s.design * lattice.h * lattice.h;
            }
            for (DesignStretch& d : tileStretches[t]) {
                d.move = std::uint32_t(pieces.move(m0 + d.move));
                batchStretches.push_back(d);
            }
            tileStats[t].clear();
            tileMoves[t].clear();
            tileStretches[t].clear();
        }
        // By move, then family and dexel (tiles come in family order, dexels within a tile in order).
        std::stable_sort(batchStretches.begin(), batchStretches.end(),
                         [](const DesignStretch& x, const DesignStretch& y) { return x.move < y.move; });
        result.designStretches.insert(result.designStretches.end(), batchStretches.begin(), batchStretches.end());
        batchStretches.clear();
        // The moves done: those before the one whose piece comes next.
        if (options.progress) options.progress(m1 == nPieces ? nMoves : pieces.move(m1), nMoves);
        // The sweeps built past the batch's end go with the next batch.
        geoms.erase(geoms.begin(), geoms.begin() + std::ptrdiff_t(m1 - m0));
        built = end - m1;
    }

    for (std::size_t i = 0; i < nMoves; ++i) {
        const MoveStats& ms = result.moves[i];
        const Move& mv = path.moves[i];
        result.bounded += ms.bounded;
        result.visited += ms.visited;
        result.changed += ms.changed;
        result.removedVolume += ms.removed;
        result.shankVolume += ms.shankVolume;
        result.holderVolume += ms.holderVolume;
        if (mv.rapid && ms.removed > options.collisionVolume)
            result.collisions.push_back({i, mv.source, CollisionKind::Rapid, ms.removed});
        // The holder's share is measured within the shank region's (ToolRegions::holder).
        const double shankAlone = ms.shankVolume - ms.holderVolume;
        if (shankAlone > options.collisionVolume)
            result.collisions.push_back({i, mv.source, CollisionKind::Shank, shankAlone});
        if (ms.holderVolume > options.collisionVolume)
            result.collisions.push_back({i, mv.source, CollisionKind::Holder, ms.holderVolume});
    }
    return result;
}

}  // namespace dexelmill
