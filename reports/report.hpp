#pragma once
// Aggregates JSONL result rows into per-method tables (Markdown, CSV, JSON, LaTeX).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace regbench {

struct ReportOptions {
    double recall_r_deg = 1.0;  ///< recall@(r, t): mae_r < r [deg] and mae_t < t (paper code)
    double recall_t = 0.1;
    double success_rre_deg = 5.0;  ///< rre/rte based success: rre < this [deg] and rte < next
    double success_rte = 0.1;
    int bootstrap_samples = 1000;  ///< 95% percentile-bootstrap CI of the means (fixed seed)
};

/// Mean with a 95% bootstrap confidence interval.
struct Estimate {
    double mean = 0.0;
    double lo = 0.0;
    double hi = 0.0;
};

/// One table row: one method over all its rows.
struct MethodSummary {
    std::string method;
    std::size_t pairs = 0;
    std::size_t failed = 0;  ///< status != ok (their metrics use the identity fallback)
    Estimate mae_r, mae_t, ccd, rre, rte;
    double rmse_r = 0.0, rmse_t = 0.0, chamfer = 0.0;
    double recall = 0.0;   ///< recall@(recall_r_deg, recall_t)
    double success = 0.0;  ///< rre/rte based
    double median_seconds = 0.0, mean_seconds = 0.0;
    int threads = 1;
};

/// Summaries in first-seen method order. Rows without metrics are rejected naming the row.
std::vector<MethodSummary> Summarize(const std::vector<nlohmann::json>& rows,
                                     const ReportOptions& options);

/// A one-line description of the data the rows came from (dataset, protocol, pairing, file).
std::string DescribeData(const std::vector<nlohmann::json>& rows);

std::string FormatMarkdown(const std::vector<MethodSummary>& s, const ReportOptions& o);
std::string FormatCsv(const std::vector<MethodSummary>& s);
std::string FormatLatex(const std::vector<MethodSummary>& s, const ReportOptions& o);
nlohmann::json ToJson(const std::vector<MethodSummary>& s, const ReportOptions& o);

}  // namespace regbench
