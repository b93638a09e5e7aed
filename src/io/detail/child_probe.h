/// @file child_probe.h
/// @brief Runs a program in a process of its own, so that a library that crashes on a damaged file
/// (OpenVDB frees memory twice on some damaged leaf data) ends that process, not the job.
#pragma once

#include <string>
#include <vector>

namespace dexelmill::detail {

/// @brief How the process ended.
struct ChildEnd {
    bool ran = false;      ///< false when no process could be started: nothing is known
    bool crashed = false;  ///< killed by a signal, or ended with a non-zero status (a sanitizer's)
    int signal = 0;        ///< the signal that killed it, 0 where it exited
};

/// @brief Starts the program at `path` with the arguments `args` (argv[1] on; argv[0] is `path`),
/// its standard output and error sent to /dev/null and every signal at its default, and waits for
/// it. A new program, not a fork that goes on running this one: a fork of a process with threads
/// holds the locks they held at that moment, and the worker threads of TBB, which OpenVDB uses to
/// free a tree, are not there to release them (a read in such a child hung in 1 of some 40
/// runs of the VDB tests).
ChildEnd runProcess(const std::string& path, const std::vector<std::string>& args);

}  // namespace dexelmill::detail
