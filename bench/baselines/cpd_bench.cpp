// BM_Cpd: CPD variants on the shared synthetic pair (bench/baselines/prob_pair.hpp).
//   compat none vs probreg at 717 points; dense vs auto (kd-leaf truncation) on large clouds.
#include <benchmark/benchmark.h>
#include <omp.h>

#include "bench/baselines/prob_pair.hpp"
#include "runners/registry.hpp"

namespace regbench {
namespace {

void BM_Cpd(benchmark::State& state, const nlohmann::json& params) {
    const auto points = static_cast<Eigen::Index>(state.range(0));
    const int threads = static_cast<int>(state.range(1));
    const BenchPair pair = MakeBenchPair(points);
    auto method = CreateMethod("cpd", params);
    const int saved = omp_get_max_threads();
    omp_set_num_threads(threads);
    AlignResult r;
    for (auto _ : state) {
        r = method->Align(pair.source, pair.target);
        benchmark::DoNotOptimize(r);
    }
    omp_set_num_threads(saved);
    ReportAlign(state, pair, r);
    state.counters["sigma2"] = r.extra.value("sigma2", 0.0);
    state.counters["truncated_its"] = r.extra.value("truncated_iterations", 0);
    state.counters["kernel_evals"] = r.extra.value("kernel_evaluations", 0.0);
}

const nlohmann::json kDefaults = nlohmann::json::object();
const nlohmann::json kProbreg = {{"compat", "probreg"}};
const nlohmann::json kDense = {{"e_step", "dense"}};
const nlohmann::json kTruncated = {{"e_step", "truncated"}};
/// 100k points: starting from sqsum would run dense iterations of 2e10 kernel evaluations
/// each, so this case starts from a given sigma^2 and is truncated from the first iteration.
const nlohmann::json kGivenSigma2 = {{"sigma2", 0.005}};

BENCHMARK_CAPTURE(BM_Cpd, none, kDefaults)
    ->Args({717, 1})
    ->Args({717, 2})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_Cpd, probreg, kProbreg)
    ->Args({717, 1})
    ->Args({717, 2})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
// Accuracy/time cost of truncation where dense is still feasible (auto = dense below 20k).
BENCHMARK_CAPTURE(BM_Cpd, dense, kDense)
    ->Args({10000, 2})
    ->Args({20000, 2})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Cpd, truncated, kTruncated)
    ->Args({10000, 2})
    ->Args({20000, 2})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Cpd, auto, kDefaults) -> Args({20000, 2}) -> ArgNames({"points", "threads"})
    -> Unit(benchmark::kMillisecond) -> UseRealTime() -> Iterations(1);
BENCHMARK_CAPTURE(BM_Cpd, auto_sigma2_0_005, kGivenSigma2)
    ->Args({100000, 2})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace regbench
