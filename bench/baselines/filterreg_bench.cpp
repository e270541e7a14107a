// FilterReg timing: one synthetic pair (bumpy ellipsoid, independent samples of the surface,
// 30 degrees about z plus a translation), built before the timed loop.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <string>

#include "core/metrics.hpp"
#include "core/transform.hpp"
#include "runners/registry.hpp"
#include "tests/testing/synthetic.hpp"

namespace regbench {
namespace {

constexpr std::uint64_t kSeed = 11;
constexpr double kAngleDeg = 30.0;

void BM_FilterReg(benchmark::State& state, const std::string& params) {
    const Eigen::Index n = state.range(0);
    omp_set_num_threads(static_cast<int>(state.range(1)));
    const Transform T_gt = MakeTransform(
        RotationFromAxisAngle({0.0, 0.0, 1.0}, kAngleDeg * M_PI / 180.0), {0.1, -0.05, 0.2});
    const Pair pair = testing::SyntheticPair(n, kSeed, T_gt);
    auto method = CreateMethod("filterreg", nlohmann::json::parse(params));
    AlignResult result = method->Align(pair.source, pair.target);  // warm-up
    for (auto _ : state) {
        result = method->Align(pair.source, pair.target);
        benchmark::DoNotOptimize(result.T_target_source.data());
    }
    const PairMetrics m = MotionMetrics(T_gt, result.T_target_source);
    state.counters["iterations"] = result.iterations;
    state.counters["rre_deg"] = m.rre;
    state.counters["ok"] = result.status == AlignStatus::kOk ? 1 : 0;
    omp_set_num_threads(1);
}

// probreg's defaults (fixed sigma2 = sqsum, lattice), the correct mode (compat "none":
// consistent weights, sigma2 updated) and the exact estimator, which is O(M N) while sigma is
// large and so is not run at 10000 points.
BENCHMARK_CAPTURE(BM_FilterReg, probreg_defaults, std::string("{}"))
    ->ArgsProduct({{717, 2048, 10000}, {1, 2}})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FilterReg, compat_none, std::string(R"({"compat": "none"})"))
    ->ArgsProduct({{717, 2048, 10000}, {1, 2}})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FilterReg, exact_compat_none,
                  std::string(R"({"compat": "none", "estimator": "exact"})"))
    ->ArgsProduct({{717, 2048}, {1, 2}})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace regbench
