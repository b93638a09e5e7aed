// libFuzzer target: the check of an OpenVDB file's framing (the lengths and offsets read before
// OpenVDB is let at the file) must judge any bytes, returning a problem or none, without throwing,
// reading past the input or taking longer than a pass over it.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "io/detail/vdb_frame.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
    (void)dexelmill::detail::vdbFramingProblem(in, size);
    return 0;
}
