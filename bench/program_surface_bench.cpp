// What `simulate` does with real programs' stocks after cutting: each program is cut once, then
// its stock is rebuilt and meshed (BM_ProgramRebuildAndMesh), or searched for what the lattice
// cannot show (BM_ProgramFinerThanLattice), on every iteration.
//
//   ./build/dexelmill_bench --benchmark_filter=BM_ProgramRebuildAndMesh --benchmark_repetitions=5
//
// Arguments: the program (0: CAMotics' bear from ../shared/testdata, skipped without it; 1: the
// bundled hood.ngc at h = 1 mm, which needs `make_examples` run into DEXELMILL_EXAMPLES_DIR, by
// default ./out) and the threads. Counters: rebuild_s and mesh_s (medians over the iterations; the
// mesh time includes its check) and their sum, triangles.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <tbb/task_arena.h>

#include "dexelmill/job/simulate.h"
#include "dexelmill/stock/fine_features.h"
#include "dexelmill/surface/contour.h"
#include "dexelmill/surface/levelset.h"
#include "dexelmill/tool/builders.h"

using namespace dexelmill;

namespace {

bool readable(const std::string& path) { return std::ifstream(path).good(); }

/// The options of program `which`, or none when its files are missing.
std::optional<SimulateOptions> programOptions(int which) {
    SimulateOptions o;
    if (which == 0) {
        const std::string bear = std::string(DEXELMILL_BENCH_TESTDATA) + "/camotics/bear/bear.camotics";
        if (!readable(bear)) return std::nullopt;
        o.inputs = {bear};
    } else {
        const char* env = std::getenv("DEXELMILL_EXAMPLES_DIR");
        const std::string hood = std::string(env ? env : "out") + "/hood.ngc";
        if (!readable(hood)) return std::nullopt;
        o.inputs = {hood};
        o.stockBox = Box{Vec3(0.0), Vec3(1694.0, 890.0, 870.0)};
        o.tools.emplace(1, ballEndMill(50.8));
        o.resolution = 1.0;
    }
    return o;
}

/// Cuts program `which` once per process and keeps its stock (null when its files are missing).
const TriDexelStock* cutStock(int which) {
    static std::map<int, std::optional<TriDexelStock>> stocks;
    auto it = stocks.find(which);
    if (it == stocks.end()) {
        std::optional<TriDexelStock> stock;
        if (std::optional<SimulateOptions> o = programOptions(which)) stock = runSimulation(*o).stock;
        it = stocks.emplace(which, std::move(stock)).first;
    }
    return it->second ? &*it->second : nullptr;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

/// The stock of the program the benchmark's first argument names, or null (the benchmark skipped)
/// when its files are missing.
const TriDexelStock* stockOrSkip(benchmark::State& state) {
    const TriDexelStock* stock = cutStock(int(state.range(0)));
    if (!stock) state.SkipWithError("the program's files are missing");
    return stock;
}

/// Both programs on one thread and on two, timed by the wall clock.
void programsAndThreads(benchmark::internal::Benchmark* b) {
    b->ArgNames({"program", "threads"})
        ->Args({0, 1})
        ->Args({0, 2})
        ->Args({1, 1})
        ->Args({1, 2})
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
}

}  // namespace

static void BM_ProgramRebuildAndMesh(benchmark::State& state) {
    const TriDexelStock* stock = stockOrSkip(state);
    if (!stock) return;
    tbb::task_arena arena(int(state.range(1)));
    std::vector<double> rebuildS, meshS, both;
    double tris = 0.0;
    for (auto _ : state) {
        arena.execute([&] {
            const auto t0 = std::chrono::steady_clock::now();
            const LevelSet ls = rebuildLevelSet(*stock);
            const auto t1 = std::chrono::steady_clock::now();
            const Mesh mesh = contourStock(ls, *stock);
            const auto t2 = std::chrono::steady_clock::now();
            rebuildS.push_back(std::chrono::duration<double>(t1 - t0).count());
            meshS.push_back(std::chrono::duration<double>(t2 - t1).count());
            both.push_back(std::chrono::duration<double>(t2 - t0).count());
            tris = double(mesh.triangles.size());
        });
    }
    state.counters["rebuild_s"] = median(rebuildS);
    state.counters["mesh_s"] = median(meshS);
    state.counters["both_s"] = median(both);
    state.counters["triangles"] = tris;
}
BENCHMARK(BM_ProgramRebuildAndMesh)->Apply(programsAndThreads);

static void BM_ProgramFinerThanLattice(benchmark::State& state) {
    const TriDexelStock* stock = stockOrSkip(state);
    if (!stock) return;
    tbb::task_arena arena(int(state.range(1)));
    FineFeatures found;
    for (auto _ : state) arena.execute([&] { found = finerThanLattice(*stock); });
    state.counters["material_stretches"] = double(found.material.count);
    state.counters["gap_stretches"] = double(found.gaps.count);
}
BENCHMARK(BM_ProgramFinerThanLattice)->Apply(programsAndThreads);
