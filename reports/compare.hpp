#pragma once
// The regression gate behind `regbench compare`: paired tests of two result sets measured on
// the same frozen pairs (a baseline and a candidate), per method and metric.
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace regbench {

struct CompareOptions {
    /// Error metrics compared (all lower-is-better).
    std::vector<std::string> metrics = {"mae_r", "mae_t", "ccd", "rre", "rte"};
    double alpha = 0.05;  ///< a change is significant when Wilcoxon p < alpha and the CI excludes 0
    int bootstrap_samples = 2000;    ///< paired-bootstrap resamples of the mean difference
    std::uint64_t seed = 20230103;   ///< bootstrap seed (streams derive from method/metric)
    double default_tolerance = 0.0;  ///< allowed mean increase for metrics not in `tolerance`
    std::map<std::string, double> tolerance;  ///< per-metric allowed mean increase (metric units)
};

/// One (method, metric) comparison over the pairs both files share.
struct MetricChange {
    std::string method;
    std::string metric;
    std::size_t pairs = 0;  ///< matched pairs with a finite metric on both sides
    double base_mean = 0.0;
    double new_mean = 0.0;
    double diff_mean = 0.0;           ///< mean of (new - base); > 0 means worse
    double ci_lo = 0.0, ci_hi = 0.0;  ///< 95% paired-bootstrap CI of diff_mean
    double p_value = 1.0;      ///< two-sided Wilcoxon signed-rank p of the paired differences
    bool significant = false;  ///< p < alpha and the CI excludes zero
    bool worse = false;        ///< significant and diff_mean > 0
    bool regression = false;   ///< worse and diff_mean > tolerance
    double tolerance = 0.0;
};

struct CompareResult {
    std::vector<MetricChange> changes;  ///< method order of the baseline, then metric order
    std::size_t matched_rows = 0;
    std::size_t base_only = 0;  ///< baseline rows with no candidate row (reported, not tested)
    std::size_t new_only = 0;
    std::size_t failures_base = 0;  ///< matched rows with status != ok
    std::size_t failures_new = 0;
    bool Regressed() const;
};

/// Matches rows by (pair-file id, pair, method) and tests every method and metric.
/// Throws std::runtime_error when the two sets were measured on different pair files (naming
/// both), when a key repeats inside one set (naming the set), or when nothing matches.
CompareResult CompareResults(const std::vector<nlohmann::json>& base,
                             const std::vector<nlohmann::json>& candidate,
                             const CompareOptions& options,
                             const std::string& base_name = "baseline",
                             const std::string& new_name = "candidate");

/// "mae_r=0.5,ccd=0.001" or a bare number (every metric) into `options`.
void ParseTolerance(const std::string& text, CompareOptions* options);

/// Markdown: every changed (significant) metric, then a one-line verdict.
std::string FormatCompareMarkdown(const CompareResult& r, const CompareOptions& o);

/// Every comparison as JSON (for CI dashboards).
nlohmann::json CompareToJson(const CompareResult& r, const CompareOptions& o);

}  // namespace regbench
