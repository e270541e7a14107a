// Micro-benchmark of the float exp kernel behind the kernel sums (gmm/gauss_sum.hpp).
// The fused CPD E-step built on them is benchmarked in bench/baselines/cpd_estep_bench.cpp.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "gmm/gauss_sum.hpp"

namespace regbench {
namespace {

/// The exp kernel alone: FastExp vs std::exp over 717^2 arguments in [-20, 0].
void BM_Exp(benchmark::State& state, bool fast) {
    std::vector<float> x(717 * 717), y(x.size());
    for (size_t i = 0; i < x.size(); ++i) x[i] = -20.0f * static_cast<float>(i) / x.size();
    for (auto _ : state) {
        if (fast) {
            for (size_t i = 0; i < x.size(); ++i) y[i] = FastExp(x[i]);
        } else {
            for (size_t i = 0; i < x.size(); ++i) y[i] = std::exp(x[i]);
        }
        benchmark::DoNotOptimize(y.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * x.size()));
}
BENCHMARK_CAPTURE(BM_Exp, fast_exp, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Exp, std_exp, false)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace regbench
