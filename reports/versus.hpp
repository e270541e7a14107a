#pragma once
// Method against method on the same pairs (`regbench report --versus A,B`,
// `regbench.compare_methods`): per metric the paired difference A - B on the pairs both methods
// ran, its bootstrap CI, the Wilcoxon signed-rank p and the per-pair wins, ties and losses.
// `regbench compare` is the other paired test: one method, two result sets (a regression gate).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "reports/statistics.hpp"
#include "reports/table.hpp"
#include "runners/result_row.hpp"

namespace regbench {

struct VersusOptions {
    /// Error metrics compared (lower is better), as `compare`.
    std::vector<std::string> metrics = {"mae_r", "mae_t", "ccd", "rre", "rte"};
    int bootstrap_samples = 2000;                ///< paired-bootstrap resamples of the mean
    std::uint64_t seed = kDefaultBootstrapSeed;  ///< streams derive from A/B/metric
};

/// One metric of A against B over their common pairs.
struct VersusMetric {
    std::string metric;
    std::size_t pairs = 0;              ///< common pairs with a finite metric on both sides
    double mean_a = 0.0, mean_b = 0.0;  ///< means over those pairs
    double diff_mean = 0.0;             ///< mean of (A - B); < 0: A has the lower error
    double ci_lo = 0.0, ci_hi = 0.0;    ///< 95% percentile-bootstrap CI of diff_mean
    double p_value = 1.0;               ///< two-sided Wilcoxon signed-rank p of A - B
    double statistic = 0.0;             ///< min(R+, R-), scipy.stats.wilcoxon's statistic
    std::size_t wins = 0;               ///< pairs where A's error is lower than B's
    std::size_t ties = 0;               ///< pairs with equal errors (differences of exactly 0)
    std::size_t losses = 0;             ///< pairs where A's error is higher
};

/// A against B on one pair file and Euler convention.
struct VersusResult {
    std::string method_a, method_b;
    DataTag data;  ///< the pair file (of A's first row)
    EulerConvention euler = EulerConvention::kZyx;
    std::size_t pairs_a = 0, pairs_b = 0;    ///< pairs each method has on that file
    std::size_t common = 0;                  ///< pairs both have
    std::size_t failed_a = 0, failed_b = 0;  ///< common pairs whose call was not ok
    std::vector<VersusMetric> metrics;       ///< options.metrics order
};

/// Compares method `a` with method `b` on every pair file (content hash) and Euler convention
/// both were measured on, one result each, matching rows by pair. Rows of failed calls take
/// part with the metrics of the transform they returned (as `report` counts them); the
/// counts of failed calls are in the result. Throws std::invalid_argument when `a` equals
/// `b`, std::runtime_error naming the methods the rows hold when `a` or `b` has no rows,
/// naming both methods' pair files when they share none, and naming the pair when a method
/// has two rows of one pair (several parameter sets: compare the files separately).
std::vector<VersusResult> CompareMethods(const std::vector<ResultRow>& rows, const std::string& a,
                                         const std::string& b, const VersusOptions& options = {});

/// The comparison as a report table: a row per metric with both means, A - B with its CI,
/// the Wilcoxon p and the wins/ties/losses of A; the caption names the data and the pairs.
Table VersusTable(const VersusResult& r);

/// The comparison as JSON (what `regbench.compare_methods` returns to Python).
nlohmann::json VersusToJson(const VersusResult& r);

}  // namespace regbench
