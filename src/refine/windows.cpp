#include "refine/detail/windows.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <utility>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "dexelmill/stock/cut.h"
#include "memory/pages.h"

namespace dexelmill::detail {

namespace {

/// Windows cut at once: their material lists take kChunk x sizeof(Material) bytes (about 150 MB).
constexpr std::size_t kChunk = std::size_t(1) << 22;
/// Moves whose sweeps are built at once and shared by the buckets.
constexpr std::size_t kBatch = 4096;
/// The bucket grid's cells are this many windows long (kBucketReach x 2 reach). Smaller cells give
/// each window fewer moves to test and each move more cells to enter: bear's refinement (one
/// round, callgrind) counted 24.9, 24.6, 24.7, 25.0 and 26.0 G instructions at 2, 3, 4, 5 and 8;
/// scorpion's 21.0 at 3 and 21.1 at 8.
constexpr double kBucketReach = 3.0;

/// The material left on one window: up to kPieces disjoint intervals, offsets from the window's
/// point along its axis, in increasing order. A float offset within reach (half a spacing) is
/// exact to about 1e-8 of the reach, far below the sweep's own accuracy.
struct Material {
    static constexpr int kPieces = 4;
    std::array<float, kPieces> lo{}, hi{};
    std::uint8_t count = 0;
    bool overflow = false;  ///< more pieces than kept: the window gives no answer

    /// Removes the closed interval [a, b]: what is left of each piece is open at a and b.
    void subtract(float a, float b) {
        if (overflow || !(a <= b)) return;
        std::array<float, kPieces> nlo{}, nhi{};
        int n = 0;
        for (int i = 0; i < count; ++i) {
            if (hi[i] <= a || lo[i] >= b) {  // untouched
                if (n == kPieces) return void(overflow = true);
                nlo[n] = lo[i], nhi[n] = hi[i], ++n;
                continue;
            }
            if (lo[i] < a) {
                if (n == kPieces) return void(overflow = true);
                nlo[n] = lo[i], nhi[n] = a, ++n;
            }
            if (hi[i] > b) {
                if (n == kPieces) return void(overflow = true);
                nlo[n] = b, nhi[n] = hi[i], ++n;
            }
        }
        lo = nlo, hi = nhi, count = std::uint8_t(n);
    }
};

/// The stock box along a window, clipped to [-reach, reach]. A window in the plane of one of the
/// box's faces runs on that face, whose part surface is the face's material: the box is taken
/// closed across the window's axis, so that a vertex where the face meets a cut finds the cut's
/// edge on the face.
Material stockMaterial(const Window& w, float reach, const Box& stock) {
    Material m;
    for (int a = 0; a < 3; ++a)
        if (a != w.axis && !(w.point[a] >= stock.lo[a] && w.point[a] <= stock.hi[a])) return m;
    const double lo = std::max(double(-reach), stock.lo[w.axis] - w.point[w.axis]);
    const double hi = std::min(double(reach), stock.hi[w.axis] - w.point[w.axis]);
    if (lo < hi) {
        m.lo[0] = lo == -reach ? -reach : float(lo);
        m.hi[0] = hi == reach ? reach : float(hi);
        m.count = 1;
    }
    return m;
}

/// The crossing nearest the window's point facing its way (NaN if none): a piece's upper end for
/// an outward +axis normal, its lower end otherwise. The window's own ends are not crossings.
double nearestCrossing(const Window& w, const Material& m, float reach) {
    if (m.overflow) return std::numeric_limits<double>::quiet_NaN();
    double best = std::numeric_limits<double>::quiet_NaN();
    for (int i = 0; i < m.count; ++i) {
        const float end = w.outward ? m.hi[i] : m.lo[i];
        if (end == reach || end == -reach) continue;
        if (!(std::abs(double(end)) >= std::abs(best))) best = end;
    }
    return best;
}

/// The grid of buckets the windows of one chunk fall in.
struct Buckets {
    CoarseGrid grid;
    std::vector<std::int32_t> index;  ///< dense cell -> run of windows, or -1
    std::vector<std::uint32_t> order;  ///< windows sorted by cell
    std::vector<std::size_t> runStart;  ///< runs of `order`, one per non-empty cell (+ end)
};

Buckets bucketWindows(const std::vector<Window>& windows, std::size_t w0, std::size_t w1, double reach) {
    Buckets b;
    Box box;
    for (std::size_t i = w0; i < w1; ++i) box.expand(windows[i].point);
    b.grid = CoarseGrid(box, kBucketReach * 2.0 * reach);
    const CoarseGrid& g = b.grid;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
    reservePopulated(keyed, w1 - w0);
    keyed.resize(w1 - w0);
    tbb::parallel_for(w0, w1, [&](std::size_t i) {
        const Vec3& p = windows[i].point;
        keyed[i - w0] = {g.index({g.coord(0, p.x), g.coord(1, p.y), g.coord(2, p.z)}), std::uint32_t(i)};
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    reservePopulated(b.index, g.cellCount());
    b.index.assign(g.cellCount(), -1);
    reservePopulated(b.order, keyed.size());
    b.order.resize(keyed.size());
    for (std::size_t k = 0; k < keyed.size(); ++k) {
        b.order[k] = keyed[k].second;
        if (k == 0 || keyed[k].first != keyed[k - 1].first) {
            b.index[keyed[k].first] = std::int32_t(b.runStart.size());
            b.runStart.push_back(k);
        }
    }
    b.runStart.push_back(keyed.size());
    return b;
}

/// Where one region of a tool can reach on one move, for a test cheaper than the sweep's bound:
/// the region is the solid of revolution about the axis n between heights zlo and zhi above the
/// tip, no wider than r, and the tip runs from a to a + f.
struct SweepReach {
    Vec3 a{0.0}, f{0.0}, n{0.0, 0.0, 1.0};
    double r = 0.0, zlo = 0.0, zhi = 0.0;

    SweepReach() = default;
    SweepReach(const Tool& region, const Move& move)
        : a(move.start), f(move.feed()), n(glm::normalize(move.axis)), r(region.maxRadius()),
          zlo(region.bottom()), zhi(region.totalLength()) {}

    /// Whether the swept region may come within `slack` of q: q's height along n lies within the
    /// heights the region sweeps, and its distance from the tip's path, across n, is at most r
    /// (both widened by the slack). Exact rounding aside, never false where the sweep reaches.
    bool mayReach(const Vec3& q, double slack) const {
        const Vec3 d = q - a;
        const double z = glm::dot(d, n), fz = glm::dot(f, n);
        if (z < std::min(0.0, fz) + zlo - slack || z > std::max(0.0, fz) + zhi + slack) return false;
        const Vec3 dp = d - z * n, fp = f - fz * n;
        const double ff = glm::dot(fp, fp);
        const double u = ff > 0.0 ? std::clamp(glm::dot(dp, fp) / ff, 0.0, 1.0) : 0.0;
        const Vec3 off = dp - u * fp;
        const double reach = r + slack;
        return glm::dot(off, off) <= reach * reach;
    }
};

/// A swept interval r (line parameters) as a window's material takes it: clipped to twice the
/// reach and rounded outwards to float (the sweep is closed, and 1e-8 of a reach is far below its
/// accuracy). Both steps keep order, so an interval inside r comes out inside r's.
std::pair<float, float> roundedOut(const Interval& r, float reach) {
    return {std::nextafter(float(std::max(r.lo, -2.0 * reach)), -std::numeric_limits<float>::infinity()),
            std::nextafter(float(std::min(r.hi, 2.0 * reach)), std::numeric_limits<float>::infinity())};
}

/// Subtracts a swept interval r (line parameters) from a window's material.
void subtractRange(const Interval& r, float reach, Material& m) {
    if (r.isEmpty() || r.hi < -reach || r.lo > reach) return;
    const auto [lo, hi] = roundedOut(r, reach);
    m.subtract(lo, hi);
}

/// Subtracts one sweep from a window's material, if its cheap bound reaches the material left
/// there: the sweep's intervals lie inside the bound, so where the bound, rounded as they would
/// be, ends below the material's lowest end or starts above its highest, none of them takes any
/// (Material::subtract leaves a piece whose end only touches the interval). On bear's refinement
/// this spares 28 % of the exact solves (4.7 million instead of 6.5): moves that reach the window
/// but not the material another move left.
void subtractSweep(const MoveSweep& sweep, const Line& line, float reach, Material& m) {
    const MoveSweep::LocalLine local = sweep.toLocal(line);
    const Interval bound = sweep.bound(local);
    if (bound.isEmpty() || bound.hi < -reach || bound.lo > reach || m.count == 0 || m.overflow) return;
    const auto [lo, hi] = roundedOut(bound, reach);
    if (hi <= m.lo[0] || lo >= m.hi[std::size_t(m.count - 1)]) return;
    Interval parts[MoveSweep::kMaxParts];
    const std::size_t n = sweep.intersectParts(local, parts);
    for (std::size_t k = 0; k < n; ++k) subtractRange(parts[k], reach, m);
}

/// Subtracts the sweep of a move whose axis turns, solved as the cutting loop solves it: within
/// its tolerance, where the window still has material.
void subtractTurning(const TurningSweep& sweep, const Line& line, float reach, Material& m) {
    const Interval bound = sweep.bound(line);
    if (bound.isEmpty() || bound.hi < -reach || bound.lo > reach) return;
    std::vector<Interval> care;
    for (int i = 0; i < m.count; ++i) care.push_back({double(m.lo[std::size_t(i)]), double(m.hi[std::size_t(i)])});
    for (const LineHit& hit : sweep.intersect(line, care)) subtractRange(hit.range, reach, m);
}

}  // namespace

SweptCells::SweptCells(const Box& stock, const ToolPath& path, const ToolTable& tools, double cell, double margin)
    : grid_(stock, cell), marked_(grid_.cellCount(), 0) {
    for (const Move& mv : path.moves) {
        const auto it = tools.find(mv.tool);
        if (it == tools.end()) continue;  // exactCrossings reports it
        const Tool& tool = it->second;
        // The tool's axis segment at both ends of the move, grown by its widest radius; for a move
        // whose axis turns, a box that holds the axis at every pose (turningMoveBox with no radius).
        Box box;
        if (mv.turns()) {
            box = turningMoveBox(mv, tool.bottom(), tool.totalLength(), 0.0);
        } else {
            const Vec3 n = glm::normalize(mv.axis);
            for (const Vec3& tip : {mv.start, mv.end})
                for (double z : {tool.bottom(), tool.totalLength()}) box.expand(tip + z * n);
        }
        std::array<int, 3> c0{}, c1{};
        if (!grid_.overlap(box, tool.maxRadius() + margin, c0, c1)) continue;
        for (int z = c0[2]; z <= c1[2]; ++z)
            for (int y = c0[1]; y <= c1[1]; ++y)
                for (int x = c0[0]; x <= c1[0]; ++x) marked_[grid_.index({x, y, z})] = 1;
    }
}

bool SweptCells::reached(const Vec3& p) const {
    std::array<int, 3> c{};
    for (int a = 0; a < 3; ++a) {
        const double x = std::floor((p[a] - grid_.origin[a]) / grid_.size);
        if (!(x >= 0.0 && x < grid_.n[a])) return true;
        c[a] = int(x);
    }
    return marked_[grid_.index(c)] != 0;
}

double stockCrossing(const Window& window, double reach, const Box& stock) {
    return nearestCrossing(window, stockMaterial(window, float(reach), stock), float(reach));
}

std::vector<double> exactCrossings(const std::vector<Window>& windows, double reach, const Box& stock,
                                   const ToolPath& path, const ToolTable& tools, bool removeShank,
                                   double turnTolerance,
                                   const std::function<void(std::size_t done, std::size_t total)>& progress) {
    std::vector<double> out;
    reservePopulated(out, windows.size());
    out.assign(windows.size(), std::numeric_limits<double>::quiet_NaN());
    if (windows.empty()) return out;
    const float freach = float(reach);
    // A holder's own sweep only measures what it meets, for the cutting loop's collisions; the
    // shank region that holds it subtracts here.
    std::map<int, ToolRegions> regions = toolRegions(path, tools);
    for (auto& [number, r] : regions) r.holder.reset();
    // Pieces of moves, as the cutting loop sweeps them (MovePieces).
    const MovePieces pieces(path, regions, turnTolerance);
    std::vector<Material> material;
    BuiltSweeps geoms;
    std::deque<SweepReach> cutReach, shankReach;
    // The slack of the cheap test: the window's half-length, and a margin for its own rounding.
    const double slack = reach * (1.0 + 1e-9) + 1e-9;
    std::vector<std::vector<std::uint32_t>> runMoves;
    std::vector<std::size_t> active;
    const std::size_t chunks = (windows.size() + kChunk - 1) / kChunk;
    const std::size_t total = chunks * pieces.size();
    std::size_t done = 0;

    for (std::size_t w0 = 0; w0 < windows.size(); w0 += kChunk) {
        const std::size_t w1 = std::min(windows.size(), w0 + kChunk);
        const Buckets b = bucketWindows(windows, w0, w1, reach);
        reservePopulated(material, w1 - w0);
        material.resize(w1 - w0);
        tbb::parallel_for(w0, w1, [&](std::size_t i) { material[i - w0] = stockMaterial(windows[i], freach, stock); });
        runMoves.assign(b.runStart.size() - 1, {});

        // geoms[i - m0] is the sweep of piece i (and the reaches alike); the first `built` of them
        // were built with the batch before.
        std::size_t built = 0;
        for (std::size_t m0 = 0, m1 = 0; m0 < pieces.size(); m0 = m1) {
            const std::size_t end = std::min(pieces.size(), m0 + kBatch);
            geoms.resize(end - m0);
            cutReach.resize(end - m0);
            shankReach.resize(end - m0);
            tbb::parallel_for(m0 + built, end, [&](std::size_t i) {
                const Move piece = pieces.piece(i);
                const ToolRegions& r = regions.at(piece.tool);
                geoms[i - m0] = MoveGeometry(r, piece, turnTolerance, pieces.regions(i));
                cutReach[i - m0] = SweepReach(*r.cutting, piece);
                if (r.shank) shankReach[i - m0] = SweepReach(*r.shank, piece);
            });
            // The batch ends before its turning sweeps could keep more linear nodes than the budget.
            m1 = m0 + movesWithinNodeBudget(geoms, end - m0);
            // Each move to the runs of windows its box (grown by the reach) overlaps, in order.
            active.clear();
            for (std::size_t i = m0; i < m1; ++i) {
                std::array<int, 3> c0{}, c1{};
                if (!b.grid.overlap(geoms[i - m0].box, reach, c0, c1)) continue;
                for (int z = c0[2]; z <= c1[2]; ++z)
                    for (int y = c0[1]; y <= c1[1]; ++y)
                        for (int x = c0[0]; x <= c1[0]; ++x) {
                            const std::int32_t run = b.index[b.grid.index({x, y, z})];
                            if (run < 0) continue;
                            if (runMoves[std::size_t(run)].empty()) active.push_back(std::size_t(run));
                            runMoves[std::size_t(run)].push_back(std::uint32_t(i - m0));
                        }
            }
            tbb::parallel_for(std::size_t(0), active.size(), [&](std::size_t k) {
                const std::size_t run = active[k];
                for (std::size_t j = b.runStart[run]; j < b.runStart[run + 1]; ++j) {
                    const std::uint32_t wi = b.order[j];
                    const Window& w = windows[wi];
                    Material& m = material[wi - w0];
                    Line line;
                    line.origin = w.point;
                    line.dir = Vec3(0.0);
                    line.dir[w.axis] = 1.0;
                    for (std::uint32_t mi : runMoves[run]) {
                        if (m.count == 0 || m.overflow) break;
                        const MoveGeometry& g = geoms[mi];
                        bool near = true;
                        for (int a = 0; a < 3; ++a) {
                            const double lo = g.box.lo[a] - (a == w.axis ? reach : 0.0);
                            const double hi = g.box.hi[a] + (a == w.axis ? reach : 0.0);
                            if (w.point[a] < lo || w.point[a] > hi) near = false;
                        }
                        if (!near) continue;
                        // The cheap reach test holds for a fixed axis only.
                        if (g.cutting.fixed && cutReach[mi].mayReach(w.point, slack))
                            subtractSweep(*g.cutting.fixed, line, freach, m);
                        else if (g.cutting.turning)
                            subtractTurning(*g.cutting.turning, line, freach, m);
                        if (!removeShank) continue;
                        if (g.shank.fixed && shankReach[mi].mayReach(w.point, slack))
                            subtractSweep(*g.shank.fixed, line, freach, m);
                        else if (g.shank.turning)
                            subtractTurning(*g.shank.turning, line, freach, m);
                    }
                }
                runMoves[run].clear();
            });
            done += m1 - m0;
            if (progress) progress(done, total);
            // The sweeps built past the batch's end go with the next batch.
            geoms.erase(geoms.begin(), geoms.begin() + std::ptrdiff_t(m1 - m0));
            cutReach.erase(cutReach.begin(), cutReach.begin() + std::ptrdiff_t(m1 - m0));
            shankReach.erase(shankReach.begin(), shankReach.begin() + std::ptrdiff_t(m1 - m0));
            built = end - m1;
        }
        tbb::parallel_for(w0, w1, [&](std::size_t i) { out[i] = nearestCrossing(windows[i], material[i - w0], freach); });
    }
    return out;
}

}  // namespace dexelmill::detail
