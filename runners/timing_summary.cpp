#include "runners/timing_summary.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace regbench {

TimingSummary SummariseTiming(const std::vector<ResultRow>& rows) {
    TimingSummary s;
    double wall = 0.0, cpu = 0.0, load_sum = 0.0;
    std::size_t load_rows = 0;
    for (const auto& row : rows) {
        if (row.status != Status::kOk) continue;
        const double w = row.result.seconds;
        const double c = row.result.cpu_seconds;
        if (!(w > 0.0) || !(c > 0.0)) continue;
        ++s.rows;
        wall += w;
        cpu += c;
        if (row.machine.contains("loadavg")) {
            load_sum += row.machine.at("loadavg").at(0).get<double>();
            ++load_rows;
        }
    }
    if (s.rows == 0) return s;
    s.mean_wall_seconds = wall / static_cast<double>(s.rows);
    s.mean_cpu_seconds = cpu / static_cast<double>(s.rows);
    s.wall_cpu_ratio = wall / cpu;
    s.oversubscribed = s.wall_cpu_ratio > kOversubscribedWallCpuRatio;
    if (s.oversubscribed) {
        s.warning = fmt::format(
            "warning: wall/CPU time = {:.2f} (> {:.1f}) over {} rows: the machine was "
            "oversubscribed, so wall times mostly measure waiting for a core; compare CPU times",
            s.wall_cpu_ratio, kOversubscribedWallCpuRatio, s.rows);
        if (load_rows > 0) {
            s.warning += fmt::format(" (1-min load at run start: {:.1f})",
                                     load_sum / static_cast<double>(load_rows));
        }
    }
    return s;
}

}  // namespace regbench
