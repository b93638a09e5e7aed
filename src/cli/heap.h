// Huge pages for the heap: see heap.cpp.
#pragma once

namespace dexelmill::cli {

/// @brief Starts the tool once more with glibc's malloc set to ask for transparent huge pages,
/// where that helps and nobody said otherwise; returns when it does not (or cannot) restart.
void restartWithHugePages(char** argv);

}  // namespace dexelmill::cli
