#pragma once
// Runs registration methods over a frozen pair file: timing, fault isolation, resume, shards.
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/metrics.hpp"
#include "core/registration.hpp"
#include "protocols/pair.hpp"
#include "runners/result_row.hpp"
#include "runners/run_options.hpp"

namespace regbench {

/// Summary of a finished run.
struct RunSummary {
    std::size_t rows_written = 0;
    std::size_t rows_skipped = 0;  ///< already present (resume)
    std::size_t failures = 0;
    double wall_seconds = 0.0;
};

/// Parses "a,b,c" (or "all": every registered method) plus an optional JSON object {"a":
/// {...params...}} into specs. Checks that every method exists and its parameters are valid
/// (instantiates each once). Throws std::invalid_argument with a clear message otherwise.
std::vector<MethodSpec> ParseMethodSpecs(const std::string& comma_list,
                                         const nlohmann::json& params_by_method);

/// What a row needs besides the pair and the call.
struct RowContext {
    std::optional<Status> status;  ///< runner-level status; unset: from the AlignResult
    int threads = 1;               ///< OpenMP threads of the call
    EulerConvention euler = EulerConvention::kZyx;
    MetricOptions metric_options;  ///< CCD clip, inlier threshold
    DataTag data;
    /// Load and cores of the machine when the run started (`run`); empty when not recorded.
    nlohmann::json machine = nlohmann::json::object();
};

/// One result row: the call's outcome plus the metrics against the pair's T_gt (computed after
/// the timed call). `run` and `score` both build rows here, so their schemas cannot drift.
ResultRow MakeResultRow(std::size_t pair_index, const Pair& pair, const MethodSpec& method,
                        const AlignResult& result, const RowContext& context);

/// The `data` tag of rows computed on `set` read from `pairs_path`.
DataTag DataTagOf(const std::string& pairs_path, const PairSet& set);

/// The pair file's recorded `scale` (`generate --scale`; 1 when it has none). Throws naming
/// the file unless it is a finite number > 0.
double PairFileScale(const std::string& pairs_path, const PairSet& set);

/// The metric options a run or score of `set` measures with: `options`, except that the
/// default CCD clip (kCcdClip, for unit-sphere objects) becomes kCcdClip times the pair file's
/// scale unless `ccd_clip_given` (`--ccd-clip` on the command line always wins).
MetricOptions PairMetricOptions(const std::string& pairs_path, const PairSet& set,
                                MetricOptions options, bool ccd_clip_given);

/// `specs` for a pair file of scale `scale` (PairFileScale; issue 54 item 1): every length
/// parameter of a registered method, i.e. one whose documentation declares it in
/// "[unit-sphere units]" (times scale) or "[unit-sphere units^2]" (times scale^2), that the user
/// did not give (MethodSpec::given) and that is at its default is multiplied, and a method with
/// a `scale_rule` then runs it as "preset" (its lengths are the data's already). A method whose
/// `scale_rule` the user gave is left as it is. Scale 1: `specs` unchanged.
std::vector<MethodSpec> PairScaledSpecs(std::vector<MethodSpec> specs, double scale);

/// ScaleWarning (core/metrics.hpp) for the median target radius of `set`'s pairs.
std::string PairScaleWarning(const PairSet& set, const MetricOptions& options);

/// The pair file's generation seed (0 when it has none): seeds the methods' per-pair streams.
std::uint64_t BenchmarkSeed(const PairSet& set);

/// Runs everything; throws std::runtime_error for bad input files before any work is done.
RunSummary RunBenchmark(const RunOptions& options);

}  // namespace regbench
