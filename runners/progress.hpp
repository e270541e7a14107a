#pragma once
// The one progress line on stderr for long work (`run`, `generate`): done/total, rate, ETA.
// Thread-safe.
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <string>
#include <thread>

namespace regbench {

class ProgressMeter {
public:
    /// `label` prefixes the line; `enabled` false makes every call a no-op.
    ProgressMeter(std::string label, std::size_t total, bool enabled = true);
    /// Adds `n` finished items; redraws at most every 0.2 s (and always at the end).
    void Advance(std::size_t n = 1);
    /// Prints the final line with the total time and a newline; stops the ticker.
    void Finish();
    ~ProgressMeter();
    ProgressMeter(const ProgressMeter&) = delete;
    ProgressMeter& operator=(const ProgressMeter&) = delete;

private:
    void Draw(bool final_line);
    /// Redraws on the same schedule while nothing finishes, so one long call (minutes of CPD
    /// on a large cloud) still shows elapsed time growing: the run is alive.
    void Tick();
    std::string label_;
    std::size_t total_;
    std::size_t done_ = 0;
    bool enabled_;
    bool finished_ = false;
    std::chrono::steady_clock::time_point start_;
    std::chrono::steady_clock::time_point last_draw_;
    std::mutex mutex_;
    std::condition_variable wake_;
    std::thread ticker_;
};

}  // namespace regbench
