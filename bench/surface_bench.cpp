// Level-set rebuild and meshing of a 512^3-lattice stock with a machined freeform surface.
//
//   ./build/dexelmill_bench --benchmark_filter=Surface
//
// Arguments: the mesher (vdb:0 the dexel mesher, vdb:1 volumeToMesh) and the threads.
// Counters: rebuild_s and mesh_s (the last iteration; the mesh time includes the mesh's check),
// grid_MB (Tree::memUsage of the result), peak_MB (peak resident memory of rebuild and mesh above
// the resident memory before them, from VmHWM after resetting it through /proc/self/clear_refs),
// triangles and folded triangles.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "dexelmill/job/simulate.h"
#include "dexelmill/surface/contour.h"
#include "dexelmill/surface/levelset.h"
#include "dexelmill/surface/mesh.h"

using namespace dexelmill;

namespace {

// The part: a 128 mm cube at h = 0.25 mm (512^3 lattice points) whose top is machined down to
// z = f(x, y) = kZ0 + kA sin(x / kLx) + kB cos(y / kLy): a freeform surface with slopes up to
// about 1.3, whose cuts along every dexel family are known in closed form.
constexpr double kSize = 128.0, kH = 0.25;
constexpr double kZ0 = 84.0, kA = 14.0, kLx = 11.0, kB = 10.0, kLy = 14.0;
constexpr double kPi = 3.14159265358979323846;

double surfaceZ(double x, double y) { return kZ0 + kA * std::sin(x / kLx) + kB * std::cos(y / kLy); }

/// Appends the parameter intervals u in [u0, u1] where sin(u + phase) < s (phase = 0) or
/// cos(u) < s (cosine = true), in the line's length units via scale (x = scale * u).
void belowIntervals(double s, bool cosine, double scale, double len,
                    std::vector<std::pair<double, double>>& out) {
    out.clear();
    if (s >= 1.0) {
        out.emplace_back(0.0, len);
        return;
    }
    if (s <= -1.0) return;
    // sin(u) < s on (pi - asin s, 2 pi + asin s) + 2 pi k; cos(u) < s on (acos s, 2 pi - acos s).
    const double lo = cosine ? std::acos(s) : kPi - std::asin(s);
    const double hi = cosine ? 2 * kPi - std::acos(s) : 2 * kPi + std::asin(s);
    for (int k = -1; (lo + 2 * kPi * k) * scale < len; ++k) {
        const double a = std::max(0.0, (lo + 2 * kPi * k) * scale);
        const double b = std::min(len, (hi + 2 * kPi * k) * scale);
        if (b > a) out.emplace_back(a, b);
    }
}

TriDexelStock makeFreeformStock() {
    TriDexelStock stock = TriDexelStock::fromBox(Box{Vec3(0.0), Vec3(kSize)}, kH);
    const Lattice& lat = stock.lattice();
    for (int a = 0; a < 3; ++a) {
        DexelFamily& fam = stock.family(axisFromIndex(a));
        tbb::parallel_for(0, fam.tilesC(), [&](int tc) {
            std::vector<std::pair<double, double>> cuts;
            const int icEnd = std::min(fam.nc(), (tc + 1) * DexelFamily::kTile);
            for (int ic = tc * DexelFamily::kTile; ic < icEnd; ++ic) {
                for (int ib = 0; ib < fam.nb(); ++ib) {
                    const double pb = lat.coord(fam.axisB(), ib), pc = lat.coord(fam.axisC(), ic);
                    if (a == 2) {  // z line at (x, y) = (pb, pc): remove above f
                        fam.subtract(ib, ic, float(surfaceZ(pb, pc)), float(kSize));
                    } else if (a == 0) {  // x line at (y, z) = (pb, pc): where A sin(x/Lx) < ...
                        belowIntervals((pc - kZ0 - kB * std::cos(pb / kLy)) / kA, false, kLx,
                                       kSize, cuts);
                        for (const auto& [lo, hi] : cuts) fam.subtract(ib, ic, float(lo), float(hi));
                    } else {  // y line at (z, x) = (pb, pc): where B cos(y/Ly) < ...
                        belowIntervals((pb - kZ0 - kA * std::sin(pc / kLx)) / kB, true, kLy, kSize,
                                       cuts);
                        for (const auto& [lo, hi] : cuts) fam.subtract(ib, ic, float(lo), float(hi));
                    }
                }
            }
        });
    }
    return stock;
}

constexpr double kMiB = 1024.0 * 1024.0;

const TriDexelStock& freeformStock() {
    static const TriDexelStock stock = makeFreeformStock();
    return stock;
}

}  // namespace

// Arguments: mesher (0 dexel, 1 vdb) and threads.
static void BM_SurfaceRebuildAndMesh512(benchmark::State& state) {
    const TriDexelStock& stock = freeformStock();
    const bool dexel = state.range(0) == 0;
    tbb::task_arena arena(int(state.range(1)));
    double rebuildS = 0.0, meshS = 0.0, peak = 0.0, grid = 0.0, tris = 0.0, active = 0.0, folded = 0.0;
    for (auto _ : state) {
        const bool peakOk = resetPeakMemory();  // trims the heap first: read the baseline after it
        const double before = currentMemoryMb() * kMiB;
        arena.execute([&] {
            const auto t0 = std::chrono::steady_clock::now();
            LevelSet ls = rebuildLevelSet(stock, {3, FamilySet::all(), "bench freeform", std::nullopt});
            const auto t1 = std::chrono::steady_clock::now();
            Mesh mesh;
            MeshCheck check;
            if (dexel) {
                ContourStats stats;
                mesh = contourStock(ls, stock, {}, &stats);
                check = stats.check;
            } else {
                mesh = meshLevelSet(ls);
                check = checkMesh(mesh);
            }
            const auto t2 = std::chrono::steady_clock::now();
            // Later iterations reuse memory the allocator kept from the first: keep the largest.
            if (peakOk) peak = std::max(peak, peakMemoryMb() * kMiB - before);
            rebuildS = std::chrono::duration<double>(t1 - t0).count();
            meshS = std::chrono::duration<double>(t2 - t1).count();
            grid = double(ls.memoryBytes());
            active = double(ls.activeVoxelCount());
            tris = double(mesh.triangles.size());
            folded = double(check.foldedTriangles);
            benchmark::DoNotOptimize(mesh);
        });
    }
    state.counters["rebuild_s"] = rebuildS;
    state.counters["mesh_s"] = meshS;
    state.counters["grid_MB"] = grid / 1e6;
    state.counters["peak_MB"] = peak / 1e6;
    state.counters["active_voxels"] = active;
    state.counters["triangles"] = tris;
    state.counters["folded"] = folded;
    state.counters["stock_MB"] = double(stock.memoryBytes()) / 1e6;
}
BENCHMARK(BM_SurfaceRebuildAndMesh512)
    ->ArgNames({"vdb", "threads"})
    ->Args({0, 1})
    ->Args({0, 2})
    ->Args({1, 1})
    ->Args({1, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);

static void BM_SurfaceMeshCheck512(benchmark::State& state) {
    const Mesh mesh = meshLevelSet(rebuildLevelSet(freeformStock()));
    for (auto _ : state) {
        const MeshCheck check = checkMesh(mesh);
        if (!check.ok()) state.SkipWithError("mesh is not a closed manifold");
        benchmark::DoNotOptimize(check);
    }
    state.counters["triangles"] = double(mesh.triangles.size());
}
BENCHMARK(BM_SurfaceMeshCheck512)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
