// Micro-benchmarks of CPD's fused E-step (baselines/cpd.hpp) on one 717 x 717 pair: the dense
// E-step floor (float polynomial exp, one thread). wide = sigma^2 = sqsum (first iteration,
// nothing pruned); narrow = sigma^2 = 1e-3 (a late iteration, kd-leaf pruning active).
#include <benchmark/benchmark.h>
#include <omp.h>

#include "baselines/cpd.hpp"
#include "core/rng.hpp"
#include "core/synthetic_shapes.hpp"
#include "core/transform.hpp"
#include "gmm/gmm_common.hpp"

namespace regbench {
namespace {

void BM_CpdEStep(benchmark::State& state, double sigma2_or_zero) {
    const auto points = static_cast<Eigen::Index>(state.range(0));
    const int threads = static_cast<int>(state.range(1));
    auto rng = MakePairRng(1, 0);
    const PointCloud Y = SmoothBlobSurface(rng, points);
    const PointCloud X = Apply(MakeTransform(RotationFromAxisAngle({0, 0, 1}, 0.5), {0.1, 0, 0}),
                               SmoothBlobSurface(rng, points));
    const double sigma2 = sigma2_or_zero > 0.0 ? sigma2_or_zero : SquaredDistanceMean(Y, X);
    GaussSumOptions opt;
    opt.mode = GaussSumMode::kDense;
    CpdEStep e_step(Y, X, opt);
    CpdPosteriors post;
    const int saved = omp_get_max_threads();
    omp_set_num_threads(threads);
    for (auto _ : state) {
        e_step.Compute(Transform::Identity(), sigma2, 0.0, post);
        benchmark::DoNotOptimize(post.np);
    }
    omp_set_num_threads(saved);
    state.counters["kernel_evals"] = static_cast<double>(post.evaluated_pairs);
    state.counters["gaussians_per_s"] = benchmark::Counter(
        static_cast<double>(post.evaluated_pairs), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK_CAPTURE(BM_CpdEStep, wide, 0.0)
    ->Args({717, 1})
    ->Args({717, 2})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_CpdEStep, narrow, 1e-3)
    ->Args({717, 1})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

}  // namespace
}  // namespace regbench
