#pragma once
// The regression gate behind `regbench compare`: paired tests of two result sets measured on
// the same frozen pairs (a baseline and a candidate), per method and metric.
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "reports/statistics.hpp"
#include "runners/result_row.hpp"

namespace regbench {

/// The documented default tolerance of each metric (docs/reports.md): 0.1 degree of MAE(R),
/// 0.2 degree of RRE, 0.001 cloud units of MAE(t) and CCD, 0.002 of RTE. `--tolerance` with
/// METRIC=VALUE replaces only the metrics it names; a bare number replaces all of them.
std::map<std::string, double> DefaultTolerances();

struct CompareOptions {
    /// Error metrics compared (all lower-is-better).
    std::vector<std::string> metrics = {"mae_r", "mae_t", "ccd", "rre", "rte"};
    double alpha = 0.05;  ///< a change is significant when Wilcoxon p < alpha and the CI excludes 0
    int bootstrap_samples = 2000;  ///< paired-bootstrap resamples of the mean difference
    std::uint64_t seed = kDefaultBootstrapSeed;  ///< streams derive from method/metric
    double default_tolerance = 0.0;  ///< allowed mean increase for metrics not in `tolerance`
    /// Per-metric allowed mean increase (metric units); starts at DefaultTolerances().
    std::map<std::string, double> tolerance = DefaultTolerances();
    /// Power at which the smallest detectable worsening is computed (see MetricChange).
    double power = 0.8;
    /// Methods with fewer matched pairs than this make the verdict INCONCLUSIVE (0: no check).
    std::size_t min_pairs = 0;
    /// When false (the default), a call that was ok in the baseline and failed, timed out or
    /// crashed in the candidate fails the gate for its method.
    bool allow_new_failures = false;
};

enum class CompareVerdict {
    kPass,          ///< exit 0
    kFail,          ///< exit 1: a regression beyond tolerance, or new failed calls
    kInconclusive,  ///< exit 3: no regression found, but the test could not have detected one
};

/// Process exit status of a verdict: 0 PASS, 1 FAIL, 3 INCONCLUSIVE.
int VerdictExitCode(CompareVerdict v);

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
    bool significant = false;  ///< p < alpha, the CI excludes zero, detectable finite
    bool worse = false;        ///< significant and diff_mean > 0
    bool regression = false;   ///< worse and diff_mean > tolerance
    double tolerance = 0.0;
    /// Smallest mean worsening the test detects with probability `power` at these pairs and
    /// alpha: +inf when the exact Wilcoxon test cannot reach p < alpha with `pairs` pairs
    /// (2 / 2^pairs >= alpha), else (z_{1-alpha/2} + z_{power}) * sd(d) / sqrt(pairs * 3/pi)
    /// (the paired normal shift formula with the Wilcoxon test's asymptotic relative
    /// efficiency 3/pi); 0 when every difference is equal.
    double detectable = 0.0;
    /// Not a regression, but the test could not have detected a worsening as large as the
    /// tolerance: detectable is infinite, or detectable > tolerance while the upper end of the
    /// 95% CI is above the tolerance too (a CI below the tolerance settles it either way).
    bool underpowered = false;
};

/// Calls of one method, over the matched pairs.
struct MethodCalls {
    std::string method;
    std::size_t pairs = 0;         ///< matched pairs
    std::size_t failed_base = 0;   ///< status != ok in the baseline
    std::size_t failed_new = 0;    ///< status != ok in the candidate
    std::size_t new_failures = 0;  ///< ok in the baseline, failed/timeout/crashed in the candidate
};

struct CompareResult {
    std::vector<MetricChange> changes;  ///< method order of the baseline, then metric order
    std::size_t matched_rows = 0;
    std::size_t base_only = 0;  ///< baseline rows with no candidate row (reported, not tested)
    std::size_t new_only = 0;
    std::size_t failures_base = 0;  ///< matched rows with status != ok
    std::size_t failures_new = 0;
    std::vector<MethodCalls> calls;   ///< per method, baseline order
    bool allow_new_failures = false;  ///< copied from the options
    std::size_t min_pairs = 0;        ///< copied from the options
    /// A regression beyond tolerance, or new failed calls while they are not allowed.
    bool Regressed() const;
    /// FAIL when Regressed(); else INCONCLUSIVE when a (method, metric) is underpowered or a
    /// method has fewer than min_pairs matched pairs; else PASS.
    CompareVerdict Verdict() const;
};

/// Matches rows by (pair-file id, pair, method) and tests every method and metric.
/// Throws std::runtime_error when the two sets were measured on different pair files (naming
/// both), when a key repeats inside one set (naming the set), or when nothing matches.
CompareResult CompareResults(const std::vector<ResultRow>& base,
                             const std::vector<ResultRow>& candidate, const CompareOptions& options,
                             const std::string& base_name = "baseline",
                             const std::string& new_name = "candidate");

/// "mae_r=0.5,ccd=0.001" (only the named metrics; the others keep their defaults) or a bare
/// number (every metric) into `options`. Throws std::invalid_argument for a negative or
/// non-numeric value and for a metric neither in DefaultTolerances() nor in options->metrics.
void ParseTolerance(const std::string& text, CompareOptions* options);

/// Markdown: every changed (significant) metric, then a one-line verdict.
std::string FormatCompareMarkdown(const CompareResult& r, const CompareOptions& o);

/// Every comparison as JSON (for CI dashboards).
nlohmann::json CompareToJson(const CompareResult& r, const CompareOptions& o);

}  // namespace regbench
