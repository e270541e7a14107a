#pragma once
// The one progress line on stderr for long work (`run`, `generate`): done/total, rate, ETA.
// Thread-safe.
#include <chrono>
#include <cstddef>
#include <mutex>
#include <string>

namespace regbench {

class ProgressMeter {
public:
    /// `label` prefixes the line; `enabled` false makes every call a no-op.
    ProgressMeter(std::string label, std::size_t total, bool enabled = true);
    /// Adds `n` finished items; redraws at most every 0.2 s (and always at the end).
    void Advance(std::size_t n = 1);
    /// Prints the final line with the total time and a newline.
    void Finish();

private:
    void Draw(bool final_line);
    std::string label_;
    std::size_t total_;
    std::size_t done_ = 0;
    bool enabled_;
    bool finished_ = false;
    std::chrono::steady_clock::time_point start_;
    std::chrono::steady_clock::time_point last_draw_;
    std::mutex mutex_;
};

}  // namespace regbench
