// The sweep solver and the cutting loop.
//
//  BM_SweepQuery/<tool>/<move>: one move, every x, y and z lattice line (h = 0.1 mm) through the
//    sweep's box is intersected with the sweep; the counter ns_per_query is the average.
//  BM_SweepQueryNormals/<tool>/<move>: the same lines, each with the Hermite data (the normals at
//    both ends of every part's interval), as the cutting loop asks for them.
//  BM_SweepBuild/<tool>/<grown>: the cost of building one convex part's sweep (MoveSweep).
//  BM_TurningQuery/<tool>/<turn in degrees>: the tilted move with its axis turning (in the cutting
//    loop's pieces), against the same move with the axis held (turn 0), over the same lines: the
//    cost of a 5-axis move per line.
//  BM_TurningShortQuery/<tool>/<turn in tenths of a degree>: the same for a move as short as a
//    real 5-axis program's, half a millimetre.
//  BM_Raster/<threads>/<h in um>: a 10,000-move ball-end finishing raster over a wavy surface on a
//    40 x 40 x 10 mm stock (400 x 400 lattice at h = 0.1): moves per second, visited/changed
//    (exact intersections per dexel that lost material) and bounded/changed (cheap bounds taken).
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "dexelmill/stock/cut.h"
#include "dexelmill/sweep/sweep.h"
#include "dexelmill/sweep/turning.h"
#include "dexelmill/tool/builders.h"
#include "dexelmill/tool/offset.h"

using namespace dexelmill;

namespace {

Tool benchTool(int kind) {
    switch (kind) {
    case 0: return flatEndMill(10.0, {30.0, 50.0});
    case 1: return ballEndMill(10.0, {30.0, 50.0});
    case 2: return bullNoseEndMill(10.0, 2.0, {30.0, 50.0});
    default: return taperBallMill(6.0, 0.1, {30.0, 50.0});
    }
}

const char* kToolNames[] = {"flat", "ball", "bull", "taperball"};
const char* kMoveNames[] = {"ramp", "horizontal", "tilted"};

/// Every lattice line of the three families (spacing h, lattice at multiples of h) through the
/// sweep's box.
std::vector<Line> linesThrough(const Box& box, double h) {
    std::vector<Line> lines;
    for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        Vec3 dir(0.0);
        dir[a] = 1.0;
        for (double yc = std::ceil(box.lo[c] / h) * h; yc <= box.hi[c]; yc += h)
            for (double yb = std::ceil(box.lo[b] / h) * h; yb <= box.hi[b]; yb += h) {
                Line l;
                l.dir = dir;
                l.origin[a] = -100.0;
                l.origin[b] = yb;
                l.origin[c] = yc;
                lines.push_back(l);
            }
    }
    return lines;
}

/// The lines of BM_SweepQuery, each intersected with the sweep by `query(sweep, line)`, which
/// returns whether the line meets it.
template <class Query>
void sweepQuery(benchmark::State& state, Query&& query) {
    const Tool tool = benchTool(int(state.range(0)));
    const int moveKind = int(state.range(1));
    const Vec3 start(0.0);
    const Vec3 end = moveKind == 1 ? Vec3(30, 10, 0) : Vec3(30, 10, -3);
    const Vec3 axis = moveKind == 2 ? glm::normalize(Vec3(0.3, -0.2, 1.0)) : Vec3(0, 0, 1);
    const MoveSweep sweep(tool, start, end, axis);
    // The cutting-relevant box: the sweep's box below the tool's top 5 mm above the tip (the
    // rest of a 50 mm tool is above any stock and the loop would cull it by material extent).
    Box box = sweep.bounds();
    box.hi.z = std::min(box.hi.z, 8.0);
    const std::vector<Line> lines = linesThrough(box, 0.1);
    std::size_t hits = 0;
    for (auto _ : state) {
        for (const Line& l : lines) hits += query(sweep, l);
    }
    state.SetLabel(std::string(kToolNames[state.range(0)]) + "/" + kMoveNames[moveKind]);
    state.counters["queries"] = double(lines.size());
    state.counters["hit_fraction"] = double(hits) / double(lines.size() * state.iterations());
    state.counters["ns_per_query"] = benchmark::Counter(double(lines.size()) * 1e-9,
                                                        benchmark::Counter::kIsIterationInvariantRate |
                                                            benchmark::Counter::kInvert);
}

void BM_SweepQuery(benchmark::State& state) {
    sweepQuery(state, [](const MoveSweep& sweep, const Line& l) {
        const Interval iv = sweep.intersect(l);
        benchmark::DoNotOptimize(iv);
        return !iv.isEmpty();
    });
}
BENCHMARK(BM_SweepQuery)->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2}})->Unit(benchmark::kMicrosecond);

void BM_SweepQueryNormals(benchmark::State& state) {
    LineHit hits[MoveSweep::kMaxParts];
    sweepQuery(state, [&hits](const MoveSweep& sweep, const Line& l) {
        const std::size_t n = sweep.intersectParts(l, hits);
        benchmark::DoNotOptimize(hits);
        return n > 0 && !hits[0].isEmpty();
    });
}
BENCHMARK(BM_SweepQueryNormals)->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2}})->Unit(benchmark::kMicrosecond);

/// BM_SweepBuild/<tool>/<grown>: building the sweep of one convex part on a short tilted move, the
/// axis varied a little per iteration. A 3-axis or 3+2 program builds one per move and region; a
/// turning move's linear nodes (turning.h) build one per node, of the part grown by a node's reach
/// with square corners (grown = 1: mitredOffsetPart by 0.01 mm).
void BM_SweepBuild(benchmark::State& state) {
    const Tool tool = benchTool(int(state.range(0)));
    const ConvexPart part = tool.convexParts().front();
    const std::vector<ProfilePiece> pieces =
        state.range(1) != 0 ? mitredOffsetPart(tool, part, 0.01)
                            : std::vector<ProfilePiece>(tool.pieces().begin() + std::ptrdiff_t(part.first),
                                                        tool.pieces().begin() + std::ptrdiff_t(part.last));
    double sink = 0.0;
    int i = 0;
    for (auto _ : state) {
        const Vec3 axis = glm::normalize(Vec3(0.3 + 1e-4 * (i++ & 255), -0.2, 1.0));
        const MoveSweep sweep(pieces, Vec3(0.0), Vec3(1.0, 0.2, -0.1), axis);
        sink += sweep.bounds().hi.x;
    }
    benchmark::DoNotOptimize(sink);
    state.counters["pieces"] = double(pieces.size());
}
BENCHMARK(BM_SweepBuild)->ArgsProduct({{0, 1, 2, 3}, {0, 1}})->Unit(benchmark::kNanosecond);

/// A tilted move from `start` to `end` with its axis turning by `turn` (rad) in the plane of the
/// tilt, ending at the tilted axis, swept within the default tolerance with its Hermite data, in
/// the pieces the cutting loop sweeps it in (MovePieces: three for 30 degrees). A turn of 0 is the
/// same move with the end axis held, swept by the fixed-axis solver: the 3+2 move the turning one
/// is compared with. Both query the same lines, those through the turning sweep's
/// box below z = 0 (a stock's top), as the cutting loop does (bound first, then the sweep where
/// the bound meets the line's material), so ns_per_query of two rows is the cost ratio per dexel
/// line.
void turningQuery(benchmark::State& state, const Vec3& start, const Vec3& end, double turn) {
    const Tool tool = benchTool(int(state.range(0)));
    Move m;
    m.start = start;
    m.end = end;
    m.axis = glm::normalize(Vec3(0.3, -0.2, 1.0));
    // The start axis: the end axis turned back by `turn` about the axis across the tilt.
    const Vec3 across = glm::normalize(glm::cross(Vec3(0, 0, 1), m.axis));
    const Vec3 towards = glm::normalize(glm::cross(across, m.axis));
    const Vec3 startAxis = std::cos(turn) * m.axis + std::sin(turn) * towards;
    Move turning = m;
    turning.startAxis = startAxis;
    ToolPath path;
    path.moves.push_back(turning);
    ToolTable table;
    table.emplace(0, tool);
    const MovePieces pieces(path, toolRegions(path, table), kDefaultTurnTolerance);
    std::vector<TurningSweep> sweeps;
    Box box;
    // The whole tool along each piece of the move, once, as the held move sweeps it: a move cut
    // into pieces is listed once per region of a tool with a shank (its cutting part's pieces, then
    // its shank's), and the shank's listing names the same stretches of u again.
    for (std::size_t k = 0; k < pieces.size(); ++k) {
        if (pieces.regions(k) == Regions::Shank) continue;
        sweeps.emplace_back(tool, pieces.piece(k));
        box.expand(sweeps.back().bounds());
    }
    // A stock with its top at z = 0, which the move enters 3 mm deep: the lines through it, and
    // on each the stretch of material the cutting loop would pass as `care`.
    box.hi.z = 0.0;
    const std::vector<Line> lines = linesThrough(box, 0.1);
    std::vector<std::vector<Interval>> care;
    for (const Line& l : lines) care.push_back({Interval{0.0, l.dir.z > 0.0 ? -l.origin.z : 200.0}});
    const MoveSweep fixed(tool, m.start, m.end, m.axis);
    std::size_t hits = 0;
    LineHit parts[MoveSweep::kMaxParts];
    // The Hermite data only for the ends within the line's care, where material takes them.
    const Interval* within = nullptr;  // the care of the line being queried
    const MoveSweep::EndFilter inCare = [&within](std::size_t, const Interval& range) {
        return (within->contains(range.lo) ? MoveSweep::kEndLo : 0u) |
               (within->contains(range.hi) ? MoveSweep::kEndHi : 0u);
    };
    std::vector<Interval> met;
    std::vector<LineHit> turned;
    // Per line, what the cutting loop does: the sweep's bound first, and only where it meets the
    // care, the query (a turning sweep's with its care clipped to the bound), with the Hermite
    // data of the ends within the care.
    for (auto _ : state) {
        for (std::size_t i = 0; i < lines.size(); ++i) {
            if (turn == 0.0) {
                if (fixed.bound(lines[i]).intersect(care[i].front()).isEmpty()) continue;
                within = &care[i].front();
                const std::size_t n = fixed.intersectParts(fixed.toLocal(lines[i]), parts, inCare);
                hits += n > 0 && !parts[0].isEmpty();
            } else {
                bool hit = false;
                for (const TurningSweep& sweep : sweeps) {
                    met.assign(1, sweep.bound(lines[i]).intersect(care[i].front()));
                    if (met.front().isEmpty()) continue;
                    sweep.intersect(lines[i], met, turned);
                    hit = hit || !turned.empty();
                }
                hits += hit;
            }
        }
    }
    state.SetLabel(std::string(kToolNames[state.range(0)]) + "/turn " + std::to_string(state.range(1)));
    state.counters["queries"] = double(lines.size());
    state.counters["hit_fraction"] = double(hits) / double(lines.size() * state.iterations());
    state.counters["ns_per_query"] = benchmark::Counter(double(lines.size()) * 1e-9,
                                                        benchmark::Counter::kIsIterationInvariantRate |
                                                            benchmark::Counter::kInvert);
}

/// BM_TurningQuery/<tool>/<turn in degrees>: the tilted move of BM_SweepQuery, (0, 0, 0) to
/// (30, 10, -3), turning (turningQuery).
void BM_TurningQuery(benchmark::State& state) {
    const double turn = double(state.range(1)) * 3.14159265358979323846 / 180.0;
    turningQuery(state, Vec3(0.0), Vec3(30, 10, -3), turn);
}
BENCHMARK(BM_TurningQuery)->ArgsProduct({{0, 1, 2}, {0, 1, 10, 30}})->Unit(benchmark::kMillisecond);

/// BM_TurningShortQuery/<tool>/<turn in tenths of a degree>: a move as short as most of a 5-axis
/// program's, 3 mm deep, (0, 0, -3) to (0.45, 0.15, -3.05), turning (turningQuery). On the
/// LinuxCNC boat and impeller programs the median feed move travels 0.55 and 0.6 mm and turns its
/// axis 0.59 and 0.17 degrees.
void BM_TurningShortQuery(benchmark::State& state) {
    const double turn = double(state.range(1)) * 0.1 * 3.14159265358979323846 / 180.0;
    turningQuery(state, Vec3(0, 0, -3), Vec3(0.45, 0.15, -3.05), turn);
}
BENCHMARK(BM_TurningShortQuery)->ArgsProduct({{0, 1, 2}, {0, 2, 6}})->Unit(benchmark::kMillisecond);

/// 100 passes along x at y steps of 0.4 mm, 100 moves of 0.4 mm each, following
/// z = 6 + 2 sin(x / 5) cos(y / 7): 10,000 feed moves (and 99 link moves).
ToolPath rasterProgram() {
    ToolPath path;
    path.files.push_back("raster.nc");
    auto surface = [](double x, double y) { return 6.0 + 2.0 * std::sin(x / 5.0) * std::cos(y / 7.0); };
    int line = 1;
    Vec3 prev(0.0);
    for (int p = 0; p < 100; ++p) {
        const double y = 0.2 + 0.4 * p;
        for (int i = 0; i < 100; ++i) {
            const bool forward = p % 2 == 0;
            const double x0 = forward ? 0.4 * i : 40.0 - 0.4 * i;
            const double x1 = forward ? x0 + 0.4 : x0 - 0.4;
            Move m;
            m.start = Vec3(x0, y, surface(x0, y));
            m.end = Vec3(x1, y, surface(x1, y));
            if (p > 0 && i == 0) {  // the step over from the previous pass
                Move link;
                link.start = prev, link.end = m.start, link.tool = 1, link.source = {0, line++};
                path.moves.push_back(link);
            }
            m.tool = 1;
            m.source = {0, line++};
            path.moves.push_back(m);
            prev = m.end;
        }
    }
    return path;
}

void BM_Raster(benchmark::State& state) {
    const int threads = int(state.range(0));
    const double h = state.range(1) * 1e-3;
    const ToolPath path = rasterProgram();
    ToolTable tools;
    tools.emplace(1, ballEndMill(6.0, {20.0, 40.0}));
    CutOptions opt;
    opt.threads = threads;
    CutResult res;
    for (auto _ : state) {
        state.PauseTiming();
        TriDexelStock stock = TriDexelStock::fromBox(Box{Vec3(0, 0, 0), Vec3(40, 40, 10)}, h);
        state.ResumeTiming();
        res = cutStock(stock, path, tools, opt);
        benchmark::DoNotOptimize(res.removedVolume);
    }
    state.counters["moves"] = double(path.moves.size());
    state.counters["moves_per_s"] =
        benchmark::Counter(double(path.moves.size()), benchmark::Counter::kIsIterationInvariantRate);
    state.counters["visited_per_changed"] = double(res.visited) / double(std::max<std::uint64_t>(1, res.changed));
    state.counters["visited"] = double(res.visited);
    state.counters["bounded_per_changed"] = double(res.bounded) / double(std::max<std::uint64_t>(1, res.changed));
}
BENCHMARK(BM_Raster)
    ->Args({1, 100})
    ->Args({2, 100})
    ->Args({1, 200})
    ->Args({2, 200})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
