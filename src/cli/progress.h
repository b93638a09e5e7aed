// A progress bar on stderr for long runs: stage, done/total, rate and ETA. Draws only when
// stderr is a terminal; redraws at most ten times a second. A stage that reports only its start
// shows that it runs; each stage's line ends with its time when the next starts.
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

    /// @brief Reports progress of a stage; a new stage name ends the last stage's line and starts
    /// a new bar.
    void update(const char* stage, std::size_t done, std::size_t total);
    /// @brief Ends the last stage's line.
    void finish();

    /// @brief True when stderr is a terminal.
    static bool stderrIsTerminal();

private:
    static std::string bar(std::size_t done, std::size_t total);
    void closeStage(std::chrono::steady_clock::time_point now);

    bool enabled_;
    bool drawn_ = false;
    bool counted_ = false;  ///< the stage has reported a count (more than its start)
    std::size_t total_ = 0;  ///< the stage's count, when it has one
    std::string stage_;
    std::chrono::steady_clock::time_point stageStart_, lastDraw_;
};

}  // namespace dexelmill::cli
