/// @file scratch.h
/// @brief Test support: a fresh, empty folder under the system's temporary folder. ctest runs
/// test cases in parallel, so each case names its own, and the process id keeps two runs of the
/// tests (two builds, say) out of each other's folders. The folders made are removed when the test
/// process exits normally.
#pragma once

#include <filesystem>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

namespace dexelmill::testing {

/// @brief Removes and recreates `temp / (prefix + name + "_" + pid)`, and returns it.
inline std::filesystem::path scratchFolder(const std::string& prefix, const std::string& name) {
    struct Made {
        std::mutex lock;
        std::vector<std::filesystem::path> folders;
        ~Made() {
            std::error_code ec;
            for (const auto& f : folders) std::filesystem::remove_all(f, ec);
        }
    };
    static Made made;
    const std::filesystem::path p =
        std::filesystem::temp_directory_path() / (prefix + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(p);
    std::filesystem::create_directories(p);
    const std::lock_guard<std::mutex> hold(made.lock);
    made.folders.push_back(p);
    return p;
}

}  // namespace dexelmill::testing
