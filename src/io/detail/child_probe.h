/// @file child_probe.h
/// @brief Runs a reader once in a child process, so that a library that crashes on a damaged file
/// (OpenVDB frees memory twice on some damaged leaf data) ends the child, not the job.
#pragma once

#include <functional>

namespace dexelmill::detail {

/// @brief How `work` ended in the child.
struct ChildEnd {
    bool ran = false;      ///< false when no child could be made (fork failed): nothing is known
    bool crashed = false;  ///< killed by a signal, or ended with a non-zero status (a sanitizer's)
    int signal = 0;        ///< the signal that killed the child, 0 where it exited
};

/// @brief Runs `work` in a forked child whose standard output and error go to /dev/null and which
/// writes no core file, and where a crash's signal ends it at once, whatever handler the parent
/// set. A C++ exception out of `work` counts as an end like a return: the caller
/// runs the work again itself to meet it with its own message. Only for work that touches nothing
/// another thread may hold locked at the fork (the child has only the calling thread); glibc
/// keeps malloc usable there.
ChildEnd runInChild(const std::function<void()>& work);

}  // namespace dexelmill::detail
