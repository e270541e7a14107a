#pragma once
// Method against method on the same pairs (`regbench report --versus A,B`,
// `regbench.compare_methods`): per metric the paired difference A - B on the pairs both methods
// ran, its 95% CI and two-sided p from one paired bootstrap (PairedBootstrap: they cannot
// disagree), a one-line verdict and the per-pair wins, ties and losses.
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
    int bootstrap_samples = 2000;                ///< paired-bootstrap resamples of the mean (CI, p)
    std::uint64_t seed = kDefaultBootstrapSeed;  ///< streams derive from A/B/metric
};

/// One metric of A against B over their common pairs.
struct VersusMetric {
    std::string metric;
    std::size_t pairs = 0;              ///< common pairs with a finite metric on both sides
    double mean_a = 0.0, mean_b = 0.0;  ///< means over those pairs
    double diff_mean = 0.0;             ///< mean of (A - B); < 0: A has the lower error
    /// 95% paired-bootstrap CI of diff_mean and the two-sided p of the same resamples
    /// (PairedBootstrap); NaN below two pairs
    double ci_lo = 0.0, ci_hi = 0.0;
    double p_value = 1.0;
    bool differs = false;  ///< the CI excludes 0 (p <= 0.05): the verdict names a better method
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
    int bootstrap_samples = 0;               ///< resamples behind every CI and p
    std::vector<VersusMetric> metrics;       ///< options.metrics order
};

/// Compares method `a` with method `b` on every pair file (content hash) and Euler convention
/// both were measured on, one result each, matching rows by pair. Rows of failed calls take
/// part with the metrics of the identity they carry (as `report` counts them); the counts of
/// failed calls are in the result. Throws std::invalid_argument when `a` equals
/// `b`, std::runtime_error naming the methods the rows hold when `a` or `b` has no rows,
/// naming both methods' pair files when they share none, and naming the pair when a method
/// has two rows of one pair (several parameter sets: compare the files separately).
std::vector<VersusResult> CompareMethods(const std::vector<ResultRow>& rows, const std::string& a,
                                         const std::string& b, const VersusOptions& options = {});

/// The one-line verdict on one metric, e.g. "mae_r: icp better than fgr (fgr - icp = 14.4,
/// 95% CI [7.43, 22.4], p = 0.0000)" or "mae_t: no difference shown (... CI contains 0 ...)".
std::string VersusVerdict(const VersusResult& r, const VersusMetric& m);

/// The comparison as a report table: a row per metric with both means, A - B with its CI and
/// p, the wins/ties/losses of A; the caption names the data and the pairs; a verdict line per
/// metric under the table (VersusVerdict).
Table VersusTable(const VersusResult& r);

/// The comparison as JSON (what `regbench.compare_methods` returns to Python); each metric
/// carries its verdict line.
nlohmann::json VersusToJson(const VersusResult& r);

}  // namespace regbench
