// libFuzzer target for the whole pipeline: a G-code program (and any subroutine files after
// "//@file NAME" lines, and a machine, harness.h) is read, cut from a small block on a coarse lattice, rebuilt,
// meshed and refined once against the exact part, on one thread, by the job the command line runs
// with `--max-memory 1G --refine 1`. It must either give a closed mesh with no degenerate triangles
// or throw dexelmill::Error; anything else aborts.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "dexelmill/error.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/tool/builders.h"
#include "harness.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace dexelmill;
    const auto files = fuzz::splitFiles(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.ngc");
    SimulateOptions job;
    job.inputs = {"fuzz.ngc"};
    job.files = fuzz::sourceOf(files);
    job.machine = fuzz::machineOf(files);
    job.stockBox = Box{Vec3(-10.0, -10.0, -6.0), Vec3(10.0, 10.0, 0.0)};
    job.resolution = 0.5;
    job.defaultTool = ballEndMill(3.0, {10.0, 20.0});
    job.threads = 1;
    job.refineRounds = 1;
    job.maxMemoryBytes = fuzz::kMemory;
    try {
        const Simulation s = runSimulation(job);
        if (!s.report.meshClosed || s.report.meshDegenerateTriangles != 0) std::abort();
    } catch (const Error&) {
    }
    return 0;
}
