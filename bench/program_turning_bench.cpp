// The cutting loop on LinuxCNC's 5-axis demos (../shared/testdata, skipped without it): each
// program's moves as read, whose tool axis turns, against the same moves with their end axis held
// (3+2), on the same stock, lattice and thread: a 5-axis move's cost per dexel on real programs.
//
//   ./build/dexelmill_bench --benchmark_filter=BM_ProgramTurning --benchmark_repetitions=5
//
// BM_ProgramTurning/<program>/<held>: program 0 boat-xyzbc.ngc (flat end D10, xyzbc-trt), 1
// boat-xyzac.ngc (bull nose D10 r2, xyzac-trt), 2 impeller-7bl-xyzac.ngc (ball end D4 from a turned
// cone, xyzac-trt), the tools and stocks their comments give; held 0 the moves as read, 1 every
// move with its end axis held. One thread, h = 0.25 mm, a fresh stock per iteration (not timed).
// Counters: ns_per_visited and ns_per_changed, the cut's time per dexel intersected exactly with a
// sweep and per dexel that lost material (the two rows of a program compared give the cost ratio
// per dexel touched); turning_moves, the moves swept turning.
#include <benchmark/benchmark.h>

#include <chrono>
#include <fstream>
#include <map>
#include <optional>
#include <string>

#include "dexelmill/job/memory.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/machine/kinematics.h"
#include "dexelmill/path/camotics.h"
#include "dexelmill/stock/cut.h"
#include "dexelmill/stock/primitive.h"
#include "dexelmill/tool/builders.h"

using namespace dexelmill;

namespace {

/// About what `simulate` chooses for these stocks by default (400 cells along the longest side).
constexpr double kResolution = 0.25;

/// A program read with its machine, its tool, and the stock it starts from.
struct Job {
    ToolPath path;
    ToolTable tools;
    std::optional<Box> box;
    std::optional<Frustum> cone;
    TriDexelStock stock() const {
        return box ? TriDexelStock::fromBox(*box, kResolution)
                   : stockFromFrustum(*cone, Lattice::fromBox(cone->bounds(), kResolution));
    }
};

/// Program `which` (see the file's comment), or none when its file is missing.
std::optional<Job> readJob(int which) {
    static const char* const files[] = {"boat-xyzbc.ngc", "boat-xyzac.ngc", "impeller-7bl-xyzac.ngc"};
    const std::string path = std::string(DEXELMILL_BENCH_TESTDATA) + "/linuxcnc/5axis-xyzac/" + files[which];
    if (!std::ifstream(path).good()) return std::nullopt;
    const MemoryBudget budget = memoryBudget(0);
    GcodeOptions gcode = jobGcodeOptions(0.001, budget);
    gcode.machine = loadMachine(which == 0 ? "xyzbc-trt" : "xyzac-trt");
    Job job;
    job.path = readProgram(path, gcode, jobAptOptions(0.001, budget)).path;
    const Tool tool = which == 0   ? flatEndMill(10.0, {25.0, 40.0})
                      : which == 1 ? bullNoseEndMill(10.0, 2.0, {25.0, 40.0})
                                   : ballEndMill(4.0, {20.0, 40.0});
    for (const Move& m : job.path.moves) job.tools.insert_or_assign(m.tool, tool);
    if (which == 0) job.box = Box{Vec3(-50.0, -28.0, -8.3), Vec3(50.0, 28.0, 0.0)};
    if (which == 1) job.box = Box{Vec3(-52.0, -28.0, -13.25), Vec3(52.0, 28.0, 0.0)};
    if (which == 2) job.cone = Frustum::make(Vec3(0.0, 0.0, -3.0), Vec3(0.0, 0.0, 1.0), 35.0, 46.0, 12.0);
    return job;
}

/// Program `which` as read (held false) or with every move's end axis held, read once per process.
const Job* job(int which, bool held) {
    static std::map<std::pair<int, bool>, std::optional<Job>> jobs;
    const auto key = std::make_pair(which, held);
    auto it = jobs.find(key);
    if (it == jobs.end()) {
        std::optional<Job> j = readJob(which);
        if (j && held)
            for (Move& m : j->path.moves) m.startAxis.reset(), m.rotary.reset();
        it = jobs.emplace(key, std::move(j)).first;
    }
    return it->second ? &*it->second : nullptr;
}

}  // namespace

static void BM_ProgramTurning(benchmark::State& state) {
    const Job* j = job(int(state.range(0)), state.range(1) != 0);
    if (!j) {
        state.SkipWithError("the program's file is missing");
        return;
    }
    CutOptions options;
    options.threads = 1;
    double seconds = 0.0;
    CutResult cut;
    for (auto _ : state) {
        state.PauseTiming();
        TriDexelStock stock = j->stock();
        state.ResumeTiming();
        const auto t0 = std::chrono::steady_clock::now();
        cut = cutStock(stock, j->path, j->tools, options);
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    const double runs = double(state.iterations());
    std::size_t turning = 0;
    for (const Move& m : j->path.moves)
        turning += sweepsTurning(m, j->tools.at(m.tool), options.turnTolerance) ? 1 : 0;
    state.counters["ns_per_visited"] = seconds * 1e9 / (runs * double(cut.visited));
    state.counters["ns_per_changed"] = seconds * 1e9 / (runs * double(cut.changed));
    state.counters["turning_moves"] = double(turning);
}
BENCHMARK(BM_ProgramTurning)
    ->ArgNames({"program", "held"})
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
