#pragma once
// Wall vs CPU time over result rows: for the report code, so tables can say which clock they
// use and warn when the machine was oversubscribed.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "runners/result_row.hpp"

namespace regbench {

/// Wall/CPU ratio above which a run counts as oversubscribed: wall time then mostly measures
/// waiting for a core, not the method.
constexpr double kOversubscribedWallCpuRatio = 1.3;

struct TimingSummary {
    std::size_t rows = 0;          ///< ok rows with both `seconds` and `cpu_seconds` > 0
    double mean_wall_seconds = 0;  ///< mean of `seconds` over those rows
    double mean_cpu_seconds = 0;   ///< mean of `cpu_seconds` over those rows
    double wall_cpu_ratio = 0;     ///< mean wall / mean CPU (0 when rows == 0)
    bool oversubscribed = false;   ///< wall_cpu_ratio > kOversubscribedWallCpuRatio
    /// One line for a report ("" when not oversubscribed), naming the ratio and the load
    /// recorded in the rows' `machine.loadavg` when present.
    std::string warning;
};

/// Summarises the ok rows of a results file (rows without `cpu_seconds`, from older runs, are
/// skipped). Threaded rows (cpu_scope "process") count all the call's threads' CPU time, so
/// their ratio can fall below 1; that is not flagged.
TimingSummary SummariseTiming(const std::vector<ResultRow>& rows);

}  // namespace regbench
