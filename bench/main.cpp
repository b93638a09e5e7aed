// The benchmarks' entry point: the tool's own start (malloc's heap on huge pages where that
// helps, relaunchWithHugePageHeap), then Google Benchmark's.
#include <benchmark/benchmark.h>

#include "dexelmill/job/memory.h"

int main(int argc, char** argv) {
    dexelmill::relaunchWithHugePageHeap(argv);
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
