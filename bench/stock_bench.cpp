// Tri-dexel storage: bytes per dexel and the cost of subtracting intervals.
#include <benchmark/benchmark.h>

#include <random>

#include "dexelmill/stock/tridexel.h"

using namespace dexelmill;

static void BM_BoxStockMemory(benchmark::State& state) {
    const double n = double(state.range(0));
    std::size_t bytes = 0, dexels = 0;
    for (auto _ : state) {
        TriDexelStock s = TriDexelStock::fromBox(Box{Vec3(0.0), Vec3(n)}, 1.0);
        bytes = s.memoryBytes();
        dexels = s.dexelCount();
        benchmark::DoNotOptimize(bytes);
    }
    state.counters["bytes_per_dexel"] = double(bytes) / double(dexels);
    state.counters["dexels"] = double(dexels);
}
BENCHMARK(BM_BoxStockMemory)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond);

static void BM_DexelSubtract(benchmark::State& state) {
    TriDexelStock s = TriDexelStock::fromBox(Box{Vec3(0.0), Vec3(256.0)}, 1.0, FamilySet::only(Axis::Z));
    DexelFamily& z = s.family(Axis::Z);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> at(0.0f, 256.0f);
    for (auto _ : state) {
        const int ib = int(rng() % 256), ic = int(rng() % 256);
        const float a = at(rng);
        benchmark::DoNotOptimize(z.subtract(ib, ic, a, a + 0.5f));
    }
    state.counters["bytes_per_dexel"] = double(s.memoryBytes()) / double(s.dexelCount());
}
BENCHMARK(BM_DexelSubtract);
