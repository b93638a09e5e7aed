// Reader throughput: lines of plain G-code per second (issue: at least 2 million).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <random>
#include <string>

#include "dexelmill/path/gcode.h"

namespace {

/// A terse modal 3-axis relief program like CAMotics' bear.nc: feeds with 3 decimals,
/// occasional rapids and feed words.
std::string plainProgram(int lines) {
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> xy(0.0, 80.0), z(-17.0, 0.0);
    std::string s = "G21 G90 G17\nT1 M6\nG0 Z20\nG1 Z-1 F6000\n";
    char buf[96];
    for (int i = 0; i < lines; ++i) {
        const int kind = i % 16;
        if (kind == 0)
            std::snprintf(buf, sizeof buf, "G0 X%.3f Y%.3f Z%.3f\n", xy(rng), xy(rng), z(rng));
        else if (kind == 1)
            std::snprintf(buf, sizeof buf, "G1 X%.3f Y%.3f Z%.3f F1500\n", xy(rng), xy(rng), z(rng));
        else if (kind % 3 == 0)
            std::snprintf(buf, sizeof buf, "X%.3f Z%.3f\n", xy(rng), z(rng));
        else
            std::snprintf(buf, sizeof buf, "X%.3f Y%.3f\n", xy(rng), xy(rng));
        s += buf;
    }
    s += "M2\n";
    return s;
}

void BM_PlainGcode(benchmark::State& state) {
    const int lines = int(state.range(0));
    const std::string text = plainProgram(lines);
    for (auto _ : state) {
        const dexelmill::Program p = dexelmill::parseGcode(text, "bench.nc");
        benchmark::DoNotOptimize(p.path.moves.data());
    }
    state.counters["lines/s"] =
        benchmark::Counter(double(lines + 5) * double(state.iterations()), benchmark::Counter::kIsRate);
    state.SetBytesProcessed(std::int64_t(text.size()) * state.iterations());
}
BENCHMARK(BM_PlainGcode)->Arg(200000)->Unit(benchmark::kMillisecond);

/// Arcs: each block becomes many chords at the default 0.001 mm tolerance.
void BM_ArcGcode(benchmark::State& state) {
    std::string text = "G21 G90 G17\nG0 X10 Y0 Z0\n";
    for (int i = 0; i < 2000; ++i) text += "G3 X-10 Y0 I-10 J0\nG3 X10 Y0 I10 J0\n";
    text += "M2\n";
    std::size_t moves = 0;
    for (auto _ : state) {
        const dexelmill::Program p = dexelmill::parseGcode(text, "arcs.nc");
        moves = p.path.moves.size();
        benchmark::DoNotOptimize(p.path.moves.data());
    }
    state.counters["moves/s"] =
        benchmark::Counter(double(moves) * double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ArcGcode)->Unit(benchmark::kMillisecond);

}  // namespace
