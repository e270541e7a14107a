#include "runners/progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace regbench {

ProgressMeter::ProgressMeter(std::string label, std::size_t total, bool enabled)
    : label_(std::move(label)),
      total_(total),
      enabled_(enabled),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {
    if (enabled_) ticker_ = std::thread([this] { Tick(); });
}

ProgressMeter::~ProgressMeter() { Finish(); }

namespace {
// Redraw often on a terminal, rarely in logs (CI, Slurm), always at the end.
constexpr double kTtyRedrawSeconds = 0.2;
constexpr double kLogRedrawSeconds = 5.0;
double RedrawSeconds() {
    return isatty(fileno(stderr)) != 0 ? kTtyRedrawSeconds : kLogRedrawSeconds;
}
}  // namespace

void ProgressMeter::Tick() {
    const auto every = std::chrono::duration<double>(RedrawSeconds());
    std::unique_lock<std::mutex> lock(mutex_);
    while (!finished_) {
        if (wake_.wait_for(lock, every, [this] { return finished_; })) break;
        const auto now = std::chrono::steady_clock::now();
        if (done_ < total_ && now - last_draw_ >= every) {
            last_draw_ = now;
            Draw(false);
        }
    }
}

void ProgressMeter::Advance(std::size_t n) {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ += n;
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    const double every = RedrawSeconds();
    // The final line is Finish()'s.
    if (done_ < total_ && std::chrono::duration<double>(now - last_draw_).count() >= every) {
        last_draw_ = now;
        Draw(false);
    }
}

void ProgressMeter::Finish() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (finished_) return;
        finished_ = true;
        if (enabled_) Draw(true);
    }
    wake_.notify_all();
    if (ticker_.joinable()) ticker_.join();
}

void ProgressMeter::Draw(bool final_line) {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double rate = elapsed > 0.0 ? static_cast<double>(done_) / elapsed : 0.0;
    const double eta =
        rate > 0.0 ? static_cast<double>(total_ - std::min(done_, total_)) / rate : 0.0;
    // On a terminal redraw in place; in logs (CI, Slurm) print one line per update.
    const bool tty = isatty(fileno(stderr)) != 0;
    std::fprintf(stderr, "%s[%s] %zu/%zu done, %.1f/s, elapsed %.1f s, ETA %.1f s%s",
                 tty ? "\r" : "", label_.c_str(), done_, total_, rate, elapsed, eta,
                 (final_line || !tty) ? "\n" : "");
    std::fflush(stderr);
}

}  // namespace regbench
