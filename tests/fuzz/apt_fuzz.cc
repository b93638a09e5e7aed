// libFuzzer target: the APT CL reader, with the command line's options, must either read a
// program or throw dexelmill::Error.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "dexelmill/error.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/path/apt.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    dexelmill::AptOptions options;
    options.chordTolerance = dexelmill::SimulateOptions().chordTolerance;
    try {
        dexelmill::parseApt(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.apt", options);
    } catch (const dexelmill::Error&) {
    }
    return 0;
}
