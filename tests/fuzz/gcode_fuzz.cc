// libFuzzer target: the G-code reader, with the command line's limits, must either read a program
// or throw dexelmill::Error. Subroutine files and the machine whose rotary axes the program turns
// come from the input (harness.h).
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "dexelmill/error.h"
#include "dexelmill/path/gcode.h"
#include "harness.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto files = fuzz::splitFiles(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.ngc");
    dexelmill::GcodeOptions options = fuzz::gcodeOptions();
    options.files = fuzz::sourceOf(files);
    try {
        const std::string machine = fuzz::machineOf(files);
        if (!machine.empty()) options.machine = dexelmill::loadMachine(machine, options.files);
        dexelmill::parseGcode(files.at("fuzz.ngc"), "fuzz.ngc", options);
    } catch (const dexelmill::Error&) {
    }
    return 0;
}
