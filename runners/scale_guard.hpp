#pragma once
// Scale guard: O(N*M) methods (dense modes; CPD, GMMReg and SVR approximate by default) on
// large clouds would run for minutes to hours per call with no
// sign of life. Before the run, such calls are either refused (default) or run on clouds
// downsampled by an explicit, recorded rule.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "protocols/pair.hpp"
#include "runners/run_options.hpp"

namespace regbench {

/// Points above which an O(N*M) method is guarded. CPD takes ~4.5 s per call at 10,000 points
/// (1 thread, README); at 20,000 about 4x that, and 200,000 points would take ~30 min.
constexpr std::size_t kDefaultMaxPoints = 20000;

/// The cost class the scale guard uses for `method` (resolved parameters) in a run with
/// `options`: a registered method's (MethodCost: a dense mode, or a method without
/// approximation, is O(N*M)), an external method's own `cost`; nullopt (not guarded) for an
/// external method without one.
std::optional<CostClass> GuardedCost(const MethodSpec& method, const RunOptions& options);

/// True when `cost` is O(N*M) and a cloud of `pair` has more than `max_points` points.
bool NeedsScaleGuard(std::optional<CostClass> cost, const Pair& pair, std::size_t max_points);

/// The same guard for one call of a registered method on clouds of `source_points` and
/// `target_points` points outside a run (Python's regbench.align): throws std::invalid_argument
/// "<method> is O(N*M): source has N points, target M, above max_points K (...)" when it would
/// refuse; the caller adds how its users lift the guard.
void RequireCallScale(const MethodSpec& method, std::size_t source_points,
                      std::size_t target_points, std::size_t max_points);

/// Checks every (pair, method) call of the run. Refuses (std::runtime_error with the expected
/// cost: pairs affected, largest N x M) unless `downsample`; with it, returns the notice that
/// says which calls will be downsampled (empty when none).
std::string CheckScale(const PairSet& set, const std::vector<std::size_t>& indices,
                       const RunOptions& options);

/// The recorded rule: keeps points floor(i * n / max_points), i = 0 .. max_points-1, of each
/// cloud above max_points (a deterministic, evenly spaced stride; no RNG), with their overlap
/// labels. `note` receives {"rule": "stride", "max_points", "source_points": [n, kept],
/// "target_points": [m, kept]} for the result row.
Pair DownsampleByStride(const Pair& pair, std::size_t max_points, nlohmann::json* note);

}  // namespace regbench
