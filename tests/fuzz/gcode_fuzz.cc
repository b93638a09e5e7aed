// libFuzzer target: the G-code reader must either read a program or throw dexelmill::Error.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "dexelmill/error.h"
#include "dexelmill/path/gcode.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    dexelmill::GcodeOptions options;
    options.chordTolerance = 0.01;
    options.maxBlocks = 20000;
    options.maxArcSegments = 20000;
    options.maxMoves = 200000;
    options.maxCallDepth = 16;
    try {
        dexelmill::parseGcode(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.ngc", options);
    } catch (const dexelmill::Error&) {
    }
    return 0;
}
