// libFuzzer target: the APT CL reader, with the command line's options, must either read a
// program or throw dexelmill::Error.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "dexelmill/error.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/path/apt.h"
#include "harness.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // The command line's options for the memory the harness may use, taken once.
    static const dexelmill::AptOptions options =
        dexelmill::jobAptOptions(dexelmill::SimulateOptions().chordTolerance, dexelmill::memoryBudget(fuzz::kMemory));
    try {
        dexelmill::parseApt(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.apt", options);
    } catch (const dexelmill::Error&) {
    }
    return 0;
}
