#pragma once
// What a run is asked to do: the methods with their parameters and the run's options. Apart
// from runner.hpp so the runner's helpers (resume, scale guard) include it without the runner.
#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/metrics.hpp"
#include "core/registration.hpp"
#include "runners/isolated_call.hpp"

namespace regbench {

/// A method to run and its parameters (JSON object; missing keys take defaults).
struct MethodSpec {
    std::string name;
    nlohmann::json params = nlohmann::json::object();
    /// The keys the user gave (ParseMethodSpecs): they are never rescaled (PairScaledSpecs).
    nlohmann::json given = nlohmann::json::object();
};

/// A method the registry does not know, given by the program that calls RunBenchmark (the
/// Python module's callables). It is timed, isolated (--timeout), resumed and written like a
/// registered method; its MethodSpec in RunOptions::methods names it and records its params.
struct ExternalMethod {
    /// A new instance (one per worker, as CreateMethod makes for registered methods).
    std::function<std::unique_ptr<RegistrationMethod>()> create;
    /// Run around the fork of each isolated call (--timeout); empty when none is needed.
    ForkHooks fork_hooks;
    /// Its cost class under its params (as MethodInfo::cost of a registered method); unset:
    /// unknown, and the scale guard skips it.
    std::function<CostClass(const nlohmann::json& params)> cost;
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
    MetricOptions metric_options;  ///< CCD clip, Open3D fitness / inlier RMSE threshold
    /// `--ccd-clip` was given: the clip is used as is. Otherwise the default clip is scaled by
    /// the pair file's `scale` (PairMetricOptions, runners/runner.hpp).
    bool ccd_clip_given = false;
    /// Methods of `methods` that are not registered, by name (which must not be a registered
    /// method's). The scale guard asks their `cost`, and skips those without one.
    std::map<std::string, ExternalMethod> external_methods;
    /// For a caller that handles SIGINT/SIGTERM itself (the Python module): when set, the run
    /// installs no signal handlers and calls this after each call, before its row is written.
    /// An exception from it drops that row and ends the run with the exception (the rows
    /// written so far stay in <out>.part for `resume`).
    std::function<void()> check_interrupt;
};

}  // namespace regbench
