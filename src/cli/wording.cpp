#include "wording.h"

namespace dexelmill::cli {

std::string counted(std::size_t n, const char* noun) { return std::to_string(n) + " " + noun + (n == 1 ? "" : "s"); }

std::string moreDiagnostics(std::size_t warnings, std::size_t notes) {
    if (notes == 0) return counted(warnings, "more warning");
    if (warnings == 0) return counted(notes, "more note");
    return counted(warnings, "more warning") + " and " + counted(notes, "more note");
}

}  // namespace dexelmill::cli
