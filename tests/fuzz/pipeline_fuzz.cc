// libFuzzer target for the whole pipeline: a G-code program is read, cut from a small block on a
// coarse lattice, rebuilt and meshed, on one thread. It must either give a closed mesh with no
// degenerate triangles or throw dexelmill::Error; anything else aborts.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "dexelmill/error.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/path/gcode.h"
#include "dexelmill/tool/builders.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace dexelmill;
    // The reader's limits kept small, so that each input runs in well under a second; the cut,
    // the rebuild and the mesh are the command line's own.
    GcodeOptions read;
    read.chordTolerance = 0.01;
    read.maxBlocks = 20000;
    read.maxArcSegments = 20000;
    read.maxMoves = 2000;
    read.maxCallDepth = 16;
    read.startPosition = Vec3(0.0, 0.0, 5.0);
    SimulateOptions job;
    try {
        job.program = parseGcode(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.ngc", read);
    } catch (const Error&) {
        return 0;
    }
    job.inputs = {"fuzz.ngc"};
    job.stockBox = Box{Vec3(-10.0, -10.0, -6.0), Vec3(10.0, 10.0, 0.0)};
    job.resolution = 0.5;
    job.defaultTool = ballEndMill(3.0, {10.0, 20.0});
    job.threads = 1;
    job.maxMemoryBytes = std::size_t(1) << 30;
    try {
        const Simulation s = runSimulation(job);
        if (!s.report.meshClosed || s.report.meshDegenerateTriangles != 0) std::abort();
    } catch (const Error&) {
    }
    return 0;
}
