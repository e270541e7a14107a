// GMMReg and SVR per-pair timings on a synthetic unit-scale shape (a lumpy ellipsoid surface,
// target = R(30 deg about z) source + (0.1, -0.05, 0.2)), 1 and 2 OpenMP threads.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cmath>
#include <string>

#include "core/transform.hpp"
#include "gmm/gmm_fit.hpp"
#include "gmm/gmm_l2.hpp"
#include "runners/registry.hpp"
#include "tests/testing/shapes.hpp"

namespace regbench {
namespace {

void BM_L2Align(benchmark::State& state, const std::string& method, const std::string& params) {
    const int n = static_cast<int>(state.range(0));
    const int threads = static_cast<int>(state.range(1));
    const PointCloud Y = testing::LumpyEllipsoid(n, 2024);
    const Transform T = testing::ThirtyDegreesAboutZ();
    const PointCloud X = Apply(T, Y);
    auto m = CreateMethod(method, nlohmann::json::parse(params));
    const int saved = omp_get_max_threads();
    omp_set_num_threads(threads);
    AlignResult r = m->Align(Y, X);  // warm-up
    for (auto _ : state) {
        r = m->Align(Y, X);
        benchmark::DoNotOptimize(r.T_target_source.data());
    }
    omp_set_num_threads(saved);
    state.counters["iterations"] = r.iterations;
    state.counters["rre_deg"] =
        RotationAngleDeg(r.T_target_source.topLeftCorner<3, 3>(), T.topLeftCorner<3, 3>());
    if (r.extra.contains("evaluations")) state.counters["evaluations"] = r.extra["evaluations"];
    if (r.extra.contains("gmm_em_iterations")) {
        state.counters["em_iterations"] = r.extra["gmm_em_iterations"];
    }
    if (r.extra.contains("support_vectors_source")) {
        state.counters["sv_source"] = r.extra["support_vectors_source"];
    }
    state.SetLabel(r.stop_reason);
}

void BM_SphericalGmmFit(benchmark::State& state) {
    const int n = static_cast<int>(state.range(0));
    omp_set_num_threads(static_cast<int>(state.range(1)));
    const PointCloud Y = testing::LumpyEllipsoid(n, 2024);
    GmmFitOptions options;
    options.n_components = std::min(800, static_cast<int>(0.8 * n));
    SphericalGmm g;
    for (auto _ : state) {
        auto rng = MakePairRng(0, 0);
        g = FitSphericalGmm(Y, options, rng);
    }
    state.counters["em_iterations"] = g.iterations;
    state.counters["kmeans_iterations"] = g.kmeans_iterations;
}

void BM_GmmL2Evaluation(benchmark::State& state) {
    const int n = static_cast<int>(state.range(0));
    omp_set_num_threads(static_cast<int>(state.range(1)));
    MixtureFeatures f{testing::LumpyEllipsoid(n, 2024), Eigen::VectorXd::Constant(n, 1.0 / n)};
    const RigidGmmL2Cost cost(f, f, 0.4, L2Gradient::kExact);
    Eigen::VectorXd theta = RigidGmmL2Cost::InitialTheta(), grad;
    for (auto _ : state) benchmark::DoNotOptimize(cost(theta, grad));
    state.counters["pairs_per_s"] = benchmark::Counter(
        static_cast<double>(n) * n, benchmark::Counter::kIsIterationInvariantRate);
}

#define REGBENCH_L2_SIZES                 \
    Args({717, 1})                        \
        ->Args({717, 2})                  \
        ->Args({2048, 1})                 \
        ->Args({2048, 2})                 \
        ->Args({10000, 1})                \
        ->Args({10000, 2})                \
        ->ArgNames({"points", "threads"}) \
        ->Unit(benchmark::kMillisecond)

BENCHMARK_CAPTURE(BM_L2Align, gmmreg, std::string("gmmreg"), std::string("{}"))->REGBENCH_L2_SIZES;
// Point features cost O(M N) per evaluation: 10k-point pairs would take several seconds.
BENCHMARK_CAPTURE(BM_L2Align, gmmreg_correct, std::string("gmmreg"),
                  std::string(R"({"compat": "correct"})"))
    ->Args({717, 1})
    ->Args({717, 2})
    ->Args({2048, 1})
    ->Args({2048, 2})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_L2Align, gmmreg_correct_sklearn, std::string("gmmreg"),
                  std::string(R"({"compat": "correct", "gmm": "sklearn"})"))
    ->REGBENCH_L2_SIZES;
BENCHMARK_CAPTURE(BM_L2Align, svr, std::string("svr"), std::string("{}"))->REGBENCH_L2_SIZES;
BENCHMARK_CAPTURE(BM_L2Align, svr_correct, std::string("svr"),
                  std::string(R"({"compat": "correct"})"))
    ->REGBENCH_L2_SIZES;
BENCHMARK(BM_SphericalGmmFit)->REGBENCH_L2_SIZES;
BENCHMARK(BM_GmmL2Evaluation)->REGBENCH_L2_SIZES;

}  // namespace
}  // namespace regbench
