#include "progress.h"

#include <cstdio>
#include <unistd.h>

namespace dexelmill::cli {

namespace {

/// A rate measured over less than this (s) says more about the clock than the work: none is shown.
constexpr double kMinRateSeconds = 0.5;

}  // namespace

ProgressBar::ProgressBar(bool enabled) : enabled_(enabled) {}

ProgressBar::~ProgressBar() { finish(); }

bool ProgressBar::stderrIsTerminal() { return isatty(STDERR_FILENO) == 1; }

void ProgressBar::update(const char* stage, std::size_t done, std::size_t total) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (stage_ != stage) {
        closeStage(now);
        stage_ = stage;
        stageStart_ = now;
        lastDraw_ = now - std::chrono::seconds(1);
        counted_ = false;
    }
    // A stage that reports only its start (0 of 1) has no count to show until it ends.
    counted_ = counted_ || total > 1 || done > 0;
    if (now - lastDraw_ < std::chrono::milliseconds(100) && done < total) return;
    lastDraw_ = now;
    total_ = total;
    const double elapsed = std::chrono::duration<double>(now - stageStart_).count();
    if (!counted_) {
        std::fprintf(stderr, "\r%-8s running ...%40s", stage, "");
    } else {
        std::fprintf(stderr, "\r%-8s [%s] %zu/%zu", stage, bar(done, total).c_str(), done, total);
        if (elapsed >= kMinRateSeconds && done > 0 && done < total) {
            const double rate = double(done) / elapsed;
            std::fprintf(stderr, "  %.0f/s  ETA %.0f s", rate, double(total - done) / rate);
        }
        std::fprintf(stderr, "%20s", "");
    }
    std::fflush(stderr);
    drawn_ = true;
}

std::string ProgressBar::bar(std::size_t done, std::size_t total) {
    constexpr int kWidth = 30;
    const double frac = total ? double(done) / double(total) : 1.0;
    const int filled = int(frac * kWidth + 0.5);
    std::string s(kWidth, '.');
    for (int i = 0; i < filled && i < kWidth; ++i) s[std::size_t(i)] = '#';
    return s;
}

void ProgressBar::closeStage(std::chrono::steady_clock::time_point now) {
    if (!drawn_) return;
    // The finished stage's line stays, with its time: the bars of a run read as a log of its stages.
    const double elapsed = std::chrono::duration<double>(now - stageStart_).count();
    if (counted_) std::fprintf(stderr, "\r%-8s [%s] %zu/%zu", stage_.c_str(), bar(total_, total_).c_str(), total_, total_);
    else std::fprintf(stderr, "\r%-8s", stage_.c_str());
    std::fprintf(stderr, " done in %.2f s%40s\n", elapsed, "");
    std::fflush(stderr);
    drawn_ = false;
}

void ProgressBar::finish() {
    if (!enabled_) return;
    closeStage(std::chrono::steady_clock::now());
    stage_.clear();
}

}  // namespace dexelmill::cli
