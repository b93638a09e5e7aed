// Where the shared real-program testdata lives (../shared/testdata), for every test area.
#pragma once

#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace dexelmill::test {

/// @brief The shared testdata folder: $DEXELMILL_SHARED_TESTDATA if set (worktrees live at
/// other depths than the main checkout), else the build's definition.
inline std::string sharedData() {
    if (const char* env = std::getenv("DEXELMILL_SHARED_TESTDATA")) return env;
    return DEXELMILL_SHARED_TESTDATA;
}

/// @brief True when the folder exists; otherwise warns so the test is visibly skipped.
inline bool haveSharedData() {
    if (std::filesystem::is_directory(sharedData())) return true;
    WARN("shared testdata folder absent (" << sharedData() << "): skipped");
    return false;
}

}  // namespace dexelmill::test
