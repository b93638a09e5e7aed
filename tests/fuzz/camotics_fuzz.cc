// libFuzzer target: the CAMotics project reader must either read a project or throw
// dexelmill::Error (never a JSON library exception).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "dexelmill/error.h"
#include "dexelmill/path/camotics.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        dexelmill::parseCamoticsProject(std::string_view(reinterpret_cast<const char*>(data), size),
                                        "fuzz.camotics", "");
    } catch (const dexelmill::Error&) {
    }
    return 0;
}
