// libFuzzer target: a CAMotics project and the programs it lists, read from the input
// (harness.h: the project first, then each program after a line "//@file NAME"), with the command
// line's limits. Reading and running it must succeed or throw dexelmill::Error (never a JSON
// library exception).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "dexelmill/error.h"
#include "dexelmill/path/camotics.h"
#include "harness.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto files =
        fuzz::splitFiles(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.camotics");
    dexelmill::GcodeOptions options = fuzz::gcodeOptions();
    options.files = fuzz::sourceOf(files);
    try {
        const dexelmill::Project project = dexelmill::readCamoticsProject("fuzz.camotics", options.files);
        dexelmill::runProject(project, options);
    } catch (const dexelmill::Error&) {
    }
    return 0;
}
