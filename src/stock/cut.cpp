#include "dexelmill/stock/cut.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "dexelmill/error.h"
#include "dexelmill/sweep/sweep.h"

namespace dexelmill {

namespace {

/// A move ready to apply: the sweeps of the cutting region and of the shank (if any).
struct PreparedMove {
    std::optional<MoveSweep> cutting;
    std::optional<MoveSweep> shank;
    Box bounds;  ///< of both sweeps
};

/// A tool split into its cutting region and its shank.
struct ToolRegions {
    std::optional<Tool> cutting;
    std::optional<Tool> shank;
};

/// One tile of one family and the moves that reach it, in program order.
struct TileWork {
    int family = 0, tb = 0, tc = 0;
    std::vector<std::uint32_t> moves;
};

/// What a tile did for one of its moves.
struct TileMoveStats {
    std::uint32_t visited = 0, changed = 0;
    double removedLength = 0.0, shankLength = 0.0;
};

/// Subtracts the intervals the sweep gives for one dexel; returns the material length removed.
double subtractSweep(const MoveSweep& sweep, const Line& line, DexelTile& tile, int local, float lo, float hi,
                     Interval* parts) {
    const std::size_t n = sweep.intersectParts(line, parts);
    double removed = 0.0;
    for (std::size_t p = 0; p < n; ++p) {
        if (parts[p].isEmpty()) continue;
        const float a = std::max(float(parts[p].lo), lo), b = std::min(float(parts[p].hi), hi);
        if (a < b) removed += tile.subtract(local, a, b);
    }
    return removed;
}

}  // namespace

CutResult cutStock(TriDexelStock& stock, const ToolPath& path, const ToolTable& tools, const CutOptions& options) {
    const std::size_t nMoves = path.moves.size();
    CutResult result;
    result.moves.assign(nMoves, MoveStats{});
    if (nMoves == 0) return result;

    std::optional<tbb::task_arena> arena;
    if (options.threads > 0) arena.emplace(options.threads);
    auto run = [&](auto&& f) {
        if (arena) arena->execute(f);
        else f();
    };

    // Tools split once.
    std::map<int, ToolRegions> regions;
    for (const Move& m : path.moves) {
        if (regions.count(m.tool)) continue;
        const auto it = tools.find(m.tool);
        if (it == tools.end()) {
            throw ParseError(path.where(m.source), "the move uses tool T" + std::to_string(m.tool) +
                                                      ", which is not defined");
        }
        const Tool& t = it->second;
        ToolRegions r;
        r.cutting = t.cuttingLength() < t.totalLength() ? t.region(t.bottom(), t.cuttingLength()) : t;
        if (t.cuttingLength() < t.totalLength()) r.shank = t.region(t.cuttingLength(), t.totalLength());
        regions.emplace(m.tool, std::move(r));
    }

    // Sweeps once per move, in parallel.
    const Box stockBox = stock.lattice().cellBox();
    std::vector<PreparedMove> prepared(nMoves);
    run([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nMoves), [&](const auto& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const Move& m = path.moves[i];
                const ToolRegions& tr = regions.at(m.tool);
                PreparedMove& p = prepared[i];
                p.cutting.emplace(*tr.cutting, m);
                p.bounds = p.cutting->bounds();
                if (tr.shank) {
                    p.shank.emplace(*tr.shank, m);
                    p.bounds.expand(p.shank->bounds());
                }
                if (!p.bounds.overlaps(stockBox)) {
                    p.cutting.reset();
                    p.shank.reset();
                }
            }
        });
    });

    // Bucket the moves by the tiles their boxes overlap, family by family.
    const Lattice& lat = stock.lattice();
    std::vector<TileWork> work;
    for (int a = 0; a < 3; ++a) {
        const Axis axis = axisFromIndex(a);
        if (!stock.has(axis)) continue;
        const DexelFamily& fam = stock.family(axis);
        const std::size_t first = work.size();
        for (int tc = 0; tc < fam.tilesC(); ++tc)
            for (int tb = 0; tb < fam.tilesB(); ++tb) work.push_back({a, tb, tc, {}});
        for (std::size_t i = 0; i < nMoves; ++i) {
            if (!prepared[i].cutting) continue;
            const Box& b = prepared[i].bounds;
            const auto rb = lat.indexRange(fam.axisB(), b.lo[index(fam.axisB())], b.hi[index(fam.axisB())]);
            const auto rc = lat.indexRange(fam.axisC(), b.lo[index(fam.axisC())], b.hi[index(fam.axisC())]);
            if (rb[0] > rb[1] || rc[0] > rc[1]) continue;
            for (int tc = rc[0] / DexelTile::kTile; tc <= rc[1] / DexelTile::kTile; ++tc)
                for (int tb = rb[0] / DexelTile::kTile; tb <= rb[1] / DexelTile::kTile; ++tb)
                    work[first + std::size_t(tb) + std::size_t(fam.tilesB()) * tc].moves.push_back(std::uint32_t(i));
        }
    }

    // Cut, tile by tile.
    std::vector<std::vector<TileMoveStats>> stats(work.size());
    std::size_t totalVisits = 0;
    for (const TileWork& w : work) totalVisits += w.moves.size();
    std::atomic<std::size_t> visitsDone{0};
    std::mutex progressMutex;
    const double h = lat.h;
    run([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, work.size()), [&](const auto& r) {
            Interval parts[MoveSweep::kMaxParts];
            for (std::size_t wi = r.begin(); wi < r.end(); ++wi) {
                const TileWork& w = work[wi];
                if (w.moves.empty()) continue;
                const Axis axis = axisFromIndex(w.family);
                DexelFamily& fam = stock.family(axis);
                DexelTile& tile = fam.tile(w.tb, w.tc);
                const int ax = w.family, bx = index(fam.axisB()), cx = index(fam.axisC());
                const int ib0 = w.tb * DexelTile::kTile, ic0 = w.tc * DexelTile::kTile;
                const int ib1 = std::min(ib0 + DexelTile::kTile, fam.nb()) - 1;
                const int ic1 = std::min(ic0 + DexelTile::kTile, fam.nc()) - 1;
                std::vector<TileMoveStats>& out = stats[wi];
                out.resize(w.moves.size());
                for (std::size_t k = 0; k < w.moves.size(); ++k) {
                    if (tile.empty()) break;
                    const PreparedMove& pm = prepared[w.moves[k]];
                    const Box& b = pm.bounds;
                    auto rb = lat.indexRange(fam.axisB(), b.lo[bx], b.hi[bx]);
                    auto rc = lat.indexRange(fam.axisC(), b.lo[cx], b.hi[cx]);
                    rb = {std::max(rb[0], ib0), std::min(rb[1], ib1)};
                    rc = {std::max(rc[0], ic0), std::min(rc[1], ic1)};
                    // The box's extent along the ray, relative to the lattice origin.
                    const float lo = float(b.lo[ax] - lat.origin[ax]), hi = float(b.hi[ax] - lat.origin[ax]);
                    TileMoveStats& s = out[k];
                    for (int ic = rc[0]; ic <= rc[1]; ++ic) {
                        for (int ib = rb[0]; ib <= rb[1]; ++ib) {
                            const int local = DexelFamily::localIndex(ib, ic);
                            const SegmentSpan segs = tile.segments(local);
                            if (segs.empty() || segs[segs.size - 1].hi <= lo || segs[0].lo >= hi) continue;
                            const Line line = stock.dexelLine(axis, ib, ic);
                            ++s.visited;
                            double removed = subtractSweep(*pm.cutting, line, tile, local, lo, hi, parts);
                            if (pm.shank) {
                                const double shank = subtractSweep(*pm.shank, line, tile, local, lo, hi, parts);
                                s.shankLength += shank;
                                removed += shank;
                            }
                            if (removed > 0) {
                                ++s.changed;
                                s.removedLength += removed;
                            }
                        }
                    }
                }
                const std::size_t done = visitsDone += w.moves.size();
                if (options.progress && progressMutex.try_lock()) {
                    options.progress(totalVisits ? nMoves * done / totalVisits : nMoves, nMoves);
                    progressMutex.unlock();
                }
            }
        });
    });

    // Reduce in a fixed order: families' volumes are averaged so a move's volume does not
    // depend on which families are kept more than it must.
    const double perFamily = h * h / double(stock.families().count());
    for (std::size_t wi = 0; wi < work.size(); ++wi) {
        for (std::size_t k = 0; k < stats[wi].size(); ++k) {
            const TileMoveStats& s = stats[wi][k];
            MoveStats& m = result.moves[work[wi].moves[k]];
            m.visited += s.visited;
            m.changed += s.changed;
            m.removed += s.removedLength * perFamily;
            m.shankVolume += s.shankLength * perFamily;
        }
    }
    for (std::size_t i = 0; i < nMoves; ++i) {
        const MoveStats& m = result.moves[i];
        result.removedVolume += m.removed;
        result.visited += m.visited;
        result.changed += m.changed;
        const Move& mv = path.moves[i];
        if (mv.rapid && m.removed > 0) result.collisions.push_back({i, mv.source, CollisionKind::Rapid, m.removed});
        if (m.shankVolume > 0) result.collisions.push_back({i, mv.source, CollisionKind::Shank, m.shankVolume});
    }
    if (options.progress) options.progress(nMoves, nMoves);
    return result;
}

}  // namespace dexelmill
