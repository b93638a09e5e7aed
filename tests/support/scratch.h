/// @file scratch.h
/// @brief Test support: a fresh, empty folder under the system's temporary folder. ctest runs
/// test cases in parallel, so each case names its own.
#pragma once

#include <filesystem>
#include <string>

namespace dexelmill::testing {

/// @brief Removes and recreates `temp / (prefix + name)`, and returns it.
inline std::filesystem::path scratchFolder(const std::string& prefix, const std::string& name) {
    const std::filesystem::path p = std::filesystem::temp_directory_path() / (prefix + name);
    std::filesystem::remove_all(p);
    std::filesystem::create_directories(p);
    return p;
}

}  // namespace dexelmill::testing
