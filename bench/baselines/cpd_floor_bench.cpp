// CPD near the machine's floor: one CPD iteration at 717 points against the time this CPU
// needs for the iteration's unavoidable work, one FastExp per source-target pair
// (717^2 = 514k exps), measured in the same process, interleaved, in CPU time of the calling
// thread (CLOCK_THREAD_CPUTIME_ID), so a loaded machine slows both alike.
//   floor_ms       CPU ms of one raw FastExp pass over 717^2 arguments
//   kernel_rows_ms CPU ms of the 717 kernel columns (KernelRow) of one dense E-step alone
//   iteration_ms   CPU ms per iteration of the full rigid CPD (E-step + M-step), 30 iterations
//   ratio          iteration_ms / floor_ms  (target: < 2)
// Run: build/bench/regbench_bench --benchmark_filter=CpdFloor
#include <benchmark/benchmark.h>

#include <vector>

#include "core/cpu_time.hpp"
#include "core/rng.hpp"
#include "core/synthetic_shapes.hpp"
#include "core/transform.hpp"
#include "gmm/gauss_sum.hpp"
#include "runners/registry.hpp"

namespace regbench {
namespace {

void BM_CpdFloor(benchmark::State& state) {
    const auto points = static_cast<Eigen::Index>(state.range(0));
    auto rng = MakePairRng(1, 0);
    const PointCloud Y = SmoothBlobSurface(rng, points);
    const PointCloud X = Apply(MakeTransform(RotationFromAxisAngle({0, 0, 1}, 0.5), {0.1, 0, 0}),
                               SmoothBlobSurface(rng, points));
    // Exp arguments spread like a wide first iteration's: -|d|^2 / 2 sigma^2 in [-20, 0].
    std::vector<float> x(static_cast<size_t>(points * points)), y(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
        x[i] = -20.0f * static_cast<float>(i % 997) / 997.0f;
    }
    // C: the kernel columns alone (KernelRow for every target, as one dense E-step computes
    // them), so the iteration's excess over the floor splits into exps + distances vs the rest.
    const Eigen::Index padded = (points + kKernelRowPad - 1) / kKernelRowPad * kKernelRowPad;
    std::vector<float> sx(static_cast<size_t>(padded), kKernelRowFar), sy(sx), sz(sx),
        column(static_cast<size_t>(padded));
    const float scale = 3.0f;  // a mid-run bandwidth: exps of -|d|^2 / 2 sigma^2, sigma ~ 0.24
    for (Eigen::Index i = 0; i < points; ++i) {
        sx[static_cast<size_t>(i)] = scale * static_cast<float>(Y(i, 0));
        sy[static_cast<size_t>(i)] = scale * static_cast<float>(Y(i, 1));
        sz[static_cast<size_t>(i)] = scale * static_cast<float>(Y(i, 2));
    }
    const FloatPoints scaled{sx.data(), sy.data(), sz.data(), padded};
    constexpr int kIterations = 30;
    auto cpd = CreateMethod("cpd", {{"maxiter", kIterations}, {"tol", 0.0}});
    double floor_cpu = 0.0, rows_cpu = 0.0, cpd_cpu = 0.0;
    int cpd_iterations = 0;
    for (auto _ : state) {
        // A: the floor, repeated as often as CPD has iterations; B: one CPD run.
        const double t0 = ThreadCpuSeconds();
        double sink = 0.0;
        for (int k = 0; k < kIterations; ++k) sink += FastExpPass(x.data(), y.data(), x.size());
        benchmark::DoNotOptimize(sink);
        floor_cpu += ThreadCpuSeconds() - t0;
        const double t1 = ThreadCpuSeconds();
        for (int k = 0; k < kIterations; ++k) {
            for (Eigen::Index j = 0; j < points; ++j) {
                const Eigen::Vector3f q = scale * X.row(j).cast<float>().transpose();
                sink += KernelRow(scaled, q, column.data());
            }
        }
        benchmark::DoNotOptimize(sink);
        rows_cpu += ThreadCpuSeconds() - t1;
        const AlignResult r = cpd->Align(Y, X);
        cpd_cpu += r.cpu_seconds;
        cpd_iterations += r.iterations;
    }
    const double floor_ms =
        1e3 * floor_cpu / (static_cast<double>(state.iterations()) * kIterations);
    const double iteration_ms = 1e3 * cpd_cpu / cpd_iterations;
    state.counters["floor_ms"] = floor_ms;
    state.counters["kernel_rows_ms"] =
        1e3 * rows_cpu / (static_cast<double>(state.iterations()) * kIterations);
    state.counters["iteration_ms"] = iteration_ms;
    state.counters["ratio"] = iteration_ms / floor_ms;
    state.counters["G_exp_per_s"] = static_cast<double>(x.size()) / (floor_ms * 1e-3) * 1e-9;
}
BENCHMARK(BM_CpdFloor)->Arg(717)->ArgNames({"points"})->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
}  // namespace regbench
