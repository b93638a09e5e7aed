#include "progress.h"

#include <cstdio>
#include <unistd.h>

namespace dexelmill::cli {

ProgressBar::ProgressBar(bool enabled) : enabled_(enabled) {}

ProgressBar::~ProgressBar() { finish(); }

bool ProgressBar::stderrIsTerminal() { return isatty(STDERR_FILENO) == 1; }

void ProgressBar::update(const char* stage, std::size_t done, std::size_t total) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (stage_ != stage) {
        if (drawn_) std::fputc('\n', stderr);
        stage_ = stage;
        stageStart_ = now;
        lastDraw_ = now - std::chrono::seconds(1);
    }
    if (now - lastDraw_ < std::chrono::milliseconds(100) && done < total) return;
    lastDraw_ = now;
    const double elapsed = std::chrono::duration<double>(now - stageStart_).count();
    const double frac = total ? double(done) / double(total) : 1.0;
    const int width = 30;
    const int filled = int(frac * width + 0.5);
    char bar[width + 1];
    for (int i = 0; i < width; ++i) bar[i] = i < filled ? '#' : '.';
    bar[width] = '\0';
    const double rate = elapsed > 0 ? double(done) / elapsed : 0.0;
    const double eta = rate > 0 ? double(total - done) / rate : 0.0;
    std::fprintf(stderr, "\r%-8s [%s] %zu/%zu  %.0f/s  ETA %.0f s   ", stage, bar, done, total, rate, eta);
    std::fflush(stderr);
    drawn_ = true;
}

void ProgressBar::finish() {
    if (enabled_ && drawn_) {
        std::fprintf(stderr, "\r%80s\r", "");
        std::fflush(stderr);
    }
    drawn_ = false;
}

}  // namespace dexelmill::cli
