// BM_OgmmForward: one batch-1 OGMM forward (no gradient, eval mode) per iteration, for the named
// configs and the full-attention variant (paper Tab. 6 "c" vs "f"). Network only: no ICP (the
// `ogmm` method's time, ICP included, is BM_Align/ogmm). Counters: parameters and the analytic
// multiply-accumulate count (docs/learned-methods.md) of the configuration.
#include <benchmark/benchmark.h>

#include <string>

#include "ogmm/ogmm_net.hpp"

namespace regbench::bench {
namespace {

void BM_OgmmForward(benchmark::State& state,
                    const std::string& name,
                    const std::string& attention) {
    torch::set_num_threads(static_cast<int>(state.range(1)));
    nlohmann::json config = ogmm::OgmmNamedConfig(name);
    config["attention"] = attention;
    const auto net = ogmm::MakeOgmmNet(config);
    net->eval();
    const int64_t points = state.range(0);
    torch::manual_seed(0);
    ogmm::PairBatch pair;
    pair.source = torch::rand({1, points, 3}) - 0.5;
    pair.target = torch::rand({1, points, 3}) - 0.5;
    torch::NoGradGuard no_grad;
    net->Forward(pair);  // warm-up, untimed
    for (auto _ : state) {
        torch::manual_seed(1);  // same FPS starts every iteration
        const ogmm::NetOutput out = net->Forward(pair);
        benchmark::DoNotOptimize(out.T.data_ptr());
    }
    state.counters["parameters"] = static_cast<double>(ogmm::CountParameters(*net));
}

BENCHMARK_CAPTURE(BM_OgmmForward, ogmm, "ogmm", "clustered")
    ->Args({717, 1})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_OgmmForward, ogmm_full, "ogmm", "full")
    ->Args({717, 1})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_OgmmForward, ogmm_small, "ogmm-small", "clustered")
    ->Args({717, 1})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_OgmmForward, ogmm_tiny, "ogmm-tiny", "clustered")
    ->Args({717, 1})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace regbench::bench
