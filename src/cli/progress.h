// A progress bar on stderr for long runs: stage, done/total, rate and ETA. Draws only when
// stderr is a terminal; redraws at most ten times a second.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>

namespace dexelmill::cli {

class ProgressBar {
public:
    /// @param enabled false draws nothing (--quiet, or stderr is not a terminal).
    explicit ProgressBar(bool enabled);
    ~ProgressBar();

    /// @brief Reports progress of a stage; a new stage name starts a new bar.
    void update(const char* stage, std::size_t done, std::size_t total);
    /// @brief Clears the bar's line.
    void finish();

    /// @brief True when stderr is a terminal.
    static bool stderrIsTerminal();

private:
    bool enabled_;
    bool drawn_ = false;
    std::string stage_;
    std::chrono::steady_clock::time_point stageStart_, lastDraw_;
};

}  // namespace dexelmill::cli
