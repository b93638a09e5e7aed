/// @file cli_run.h
/// @brief Test support: the dexelmill executable run as a user runs it, in a folder of its own,
/// its exit code and what it printed kept.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <sys/wait.h>

#include "support/scratch.h"
#include "support/temp_dir.h"

namespace dexelmill::testing {

/// What one run of the executable did: its exit code (-1 where it did not exit) and its output.
struct Run {
    int code = -1;
    std::string out, err;
};

/// Runs the CLI in a folder of its own (ctest runs test cases in parallel).
class Cli {
public:
    explicit Cli(const std::string& name) : dir_(scratchFolder("dexelmill_cli_", name)) {}
    /// Runs `dexelmill ARGS` (shell words) in the folder, with the environment's variables `env`
    /// ("NAME=value ...") added.
    Run operator()(const std::string& args, const std::string& env = "") const {
        return runIn(env + " '" + DEXELMILL_CLI_PATH + "' " + args);
    }
    /// Runs a shell command line in the folder.
    Run runIn(const std::string& line) const {
        const int status = std::system(("cd '" + dir_.string() + "' && " + line + " > out.txt 2> err.txt").c_str());
        Run r;
        r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        r.out = slurp(dir_ / "out.txt");
        r.err = slurp(dir_ / "err.txt");
        return r;
    }
    void file(const std::string& name, const std::string& text) const { std::ofstream(dir_ / name) << text; }
    const std::filesystem::path& dir() const { return dir_; }

private:
    std::filesystem::path dir_;
};

}  // namespace dexelmill::testing
