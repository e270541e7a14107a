// BM_Cpd: CPD variants on the shared synthetic pair (bench/baselines/prob_pair.hpp).
//   compat none vs probreg at 717 points; dense vs auto (kd-leaf truncation) on large clouds.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "bench/baselines/prob_pair.hpp"
#include "runners/registry.hpp"

namespace regbench {
namespace {

void BM_Cpd(benchmark::State& state, const nlohmann::json& params) {
    const BenchPair pair = MakeBenchPair(static_cast<Eigen::Index>(state.range(0)));
    auto method = CreateMethod("cpd", params);
    const AlignResult r = TimeAlign(state, *method, pair);
    state.counters["sigma2"] = r.extra.value("sigma2", 0.0);
    state.counters["truncated_its"] = r.extra.value("truncated_iterations", 0);
    state.counters["kernel_evals"] = r.extra.value("kernel_evaluations", 0.0);
}

/// Registers BM_Cpd/<name> with `params` at each (points, threads) of `args`, in milliseconds
/// of real time; `once`: a single iteration (the large clouds).
void RegisterCpd(const std::string& name, const nlohmann::json& params,
                 const std::vector<std::vector<int64_t>>& args, bool once) {
    auto* b = benchmark::RegisterBenchmark(("BM_Cpd/" + name).c_str(), BM_Cpd, params);
    for (const auto& a : args) b->Args(a);
    b->ArgNames({"points", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
    if (once) b->Iterations(1);
}

const bool kRegistered = [] {
    const nlohmann::json defaults = nlohmann::json::object();
    RegisterCpd("none", defaults, {{717, 1}, {717, 2}}, false);
    RegisterCpd("probreg", {{"compat", "probreg"}}, {{717, 1}, {717, 2}}, false);
    // Accuracy/time cost of truncation where dense is still feasible (auto = dense below 20k).
    RegisterCpd("dense", {{"e_step", "dense"}}, {{10000, 2}, {20000, 2}}, true);
    RegisterCpd("truncated", {{"e_step", "truncated"}}, {{10000, 2}, {20000, 2}}, true);
    RegisterCpd("auto", defaults, {{20000, 2}}, true);
    // 100k points: starting from sqsum would run dense iterations of 2e10 kernel evaluations
    // each, so this case starts from a given sigma^2 and is truncated from the first iteration.
    RegisterCpd("auto_sigma2_0_005", {{"sigma2", 0.005}}, {{100000, 2}}, true);
    return true;
}();

}  // namespace
}  // namespace regbench
