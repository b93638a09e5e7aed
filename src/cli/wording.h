// Counts in the words the console prints them in, shared by the subcommands.
#pragma once

#include <cstddef>
#include <string>

namespace dexelmill::cli {

/// A count and its noun, plural unless the count is one: "1 move", "0 moves".
std::string counted(std::size_t n, const char* noun);

/// The diagnostics a listing left out, by kind, naming only the kinds it left out:
/// "6 more warnings and 1 more note", "3 more notes", "1 more warning".
std::string moreDiagnostics(std::size_t warnings, std::size_t notes);

}  // namespace dexelmill::cli
