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
#include "runners/isolated_call.hpp"
#include "runners/result_row.hpp"

namespace regbench {

/// A method to run and its parameters (JSON object; missing keys take defaults).
struct MethodSpec {
    std::string name;
    nlohmann::json params = nlohmann::json::object();
};

/// A method the registry does not know, given by the program that calls RunBenchmark (the
/// Python module's callables). It is timed, isolated (--timeout), resumed and written like a
/// registered method; its MethodSpec in RunOptions::methods names it and records its params.
struct ExternalMethod {
    /// A new instance (one per worker, as CreateMethod makes for registered methods).
    std::function<std::unique_ptr<RegistrationMethod>()> create;
    /// Run around the fork of each isolated call (--timeout); empty when none is needed.
    ForkHooks fork_hooks;
};

struct RunOptions {
    std::string pairs_path;           ///< frozen HDF5 pair file
    std::vector<MethodSpec> methods;  ///< run in this order for every pair
    std::string out_path;             ///< JSONL; written as <out>.part, renamed when complete
    int jobs = 1;                     ///< pairs processed in parallel (one method instance each)
    int threads_per_call = 1;         ///< OpenMP threads inside one Align call (timing: 1)
    bool resume = false;              ///< keep finished rows of <out>.part and skip them
    int shard_index = 0;              ///< process pairs with k % shard_count == shard_index
    int shard_count = 1;
    double timeout_seconds = 0.0;  ///< > 0: each call runs in a child process, killed after it
    bool progress = true;          ///< progress line (done, rate, ETA) on stderr
    /// O(N*M) methods (MethodCost) on a cloud above this many points are refused before the run
    /// starts, or downsampled when `downsample`; 0 disables the guard. See runners/scale_guard.
    std::size_t max_points = 20000;
    bool downsample = false;  ///< guard: run on stride-downsampled clouds instead of refusing
    EulerConvention euler = EulerConvention::kZyx;  ///< Euler angles of mae_r / rmse_r
    /// Methods of `methods` that are not registered, by name (which must not be a registered
    /// method's). The scale guard skips them: their cost is unknown.
    std::map<std::string, ExternalMethod> external_methods;
    /// For a caller that handles SIGINT/SIGTERM itself (the Python module): when set, the run
    /// installs no signal handlers and calls this after each call, before its row is written.
    /// An exception from it drops that row and ends the run with the exception (the rows
    /// written so far stay in <out>.part for `resume`).
    std::function<void()> check_interrupt;
};

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
    DataTag data;
    /// Load and cores of the machine when the run started (`run`); empty when not recorded.
    nlohmann::json machine = nlohmann::json::object();
};

/// One result row: the call's outcome plus the metrics against the pair's T_gt (computed after
/// the timed call). `run` and `score` both build rows here, so their schemas cannot drift.
ResultRow MakeResultRow(std::size_t pair_index,
                        const Pair& pair,
                        const MethodSpec& method,
                        const AlignResult& result,
                        const RowContext& context);

/// The `data` tag of rows computed on `set` read from `pairs_path`.
DataTag DataTagOf(const std::string& pairs_path, const PairSet& set);

/// The pair file's generation seed (0 when it has none): seeds the methods' per-pair streams.
std::uint64_t BenchmarkSeed(const PairSet& set);

/// Runs everything; throws std::runtime_error for bad input files before any work is done.
RunSummary RunBenchmark(const RunOptions& options);

}  // namespace regbench
