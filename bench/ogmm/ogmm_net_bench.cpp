// BM_OgmmForward / BM_DeepGmrForward: one batch-1 forward (no gradient, eval mode) per
// iteration, for the named configs and OGMM's full-attention variant (paper Tab. 6 "c" vs "f").
// Network only: no ICP (the methods' time, ICP included, is BM_Align/ogmm, BM_Align/deepgmr).
// Counters: parameters and the analytic multiply-accumulate count of one forward on the pair
// (ogmm/cost.hpp, formulas in docs/learned-methods.md).
#include <benchmark/benchmark.h>

#include <string>
#include <utility>

#include "ogmm/cost.hpp"
#include "ogmm/ogmm_net.hpp"
#include "ogmm/zoo.hpp"

namespace regbench::bench {
namespace {

/// Times net->Forward on a uniform random pair of state.range(0) points in [-0.5, 0.5]^3.
void TimeForward(benchmark::State& state,
                 ogmm::RegistrationNet& net,
                 const nlohmann::json& config) {
    net.eval();
    const int64_t points = state.range(0);
    torch::manual_seed(0);
    ogmm::PairBatch pair;
    pair.source = torch::rand({1, points, 3}) - 0.5;
    pair.target = torch::rand({1, points, 3}) - 0.5;
    torch::NoGradGuard no_grad;
    net.Forward(pair);  // warm-up, untimed
    for (auto _ : state) {
        torch::manual_seed(1);  // same FPS starts every iteration
        const ogmm::NetOutput out = net.Forward(pair);
        benchmark::DoNotOptimize(out.T.data_ptr());
    }
    state.counters["parameters"] = static_cast<double>(ogmm::CountParameters(net));
    state.counters["MACs"] =
        static_cast<double>(ogmm::ComputeForwardCost(config, points, points).total);
}

void BM_OgmmForward(benchmark::State& state,
                    const std::string& name,
                    const std::string& attention) {
    torch::set_num_threads(static_cast<int>(state.range(1)));
    nlohmann::json config = ogmm::OgmmNamedConfig(name);
    config["attention"] = attention;
    TimeForward(state, *ogmm::MakeOgmmNet(config), config);
}

void BM_DeepGmrForward(benchmark::State& state, const std::string& name) {
    torch::set_num_threads(static_cast<int>(state.range(1)));
    const nlohmann::json config = ogmm::NamedConfig(name);
    TimeForward(state, *ogmm::MakeNetFromConfig(config), config);
}

/// One forward of 717 points (the bench pair's size) on one thread, in milliseconds.
void Configure(benchmark::internal::Benchmark* b) {
    b->Args({717, 1})->ArgNames({"points", "threads"})->Unit(benchmark::kMillisecond);
}

// Runs before main(), like the BENCHMARK macros (see align_bench.cpp). Names as
// BM_OgmmForward/<label>, BM_DeepGmrForward/<label>.
const bool kRegistered = [] {
    struct OgmmCase {
        const char* label;
        const char* config;  ///< OgmmNamedConfig name
        const char* attention;
    };
    const OgmmCase ogmm_cases[] = {
        {"ogmm", "ogmm", "clustered"},
        {"ogmm_full", "ogmm", "full"},  // paper Tab. 6 "f"
        {"ogmm_small", "ogmm-small", "clustered"},
        {"ogmm_tiny", "ogmm-tiny", "clustered"},
    };
    for (const OgmmCase& c : ogmm_cases) {
        Configure(benchmark::RegisterBenchmark(("BM_OgmmForward/" + std::string(c.label)).c_str(),
                                               BM_OgmmForward, std::string(c.config),
                                               std::string(c.attention)));
    }
    const std::pair<const char*, const char*> deepgmr_cases[] = {
        // {label, NamedConfig name}
        {"deepgmr", "deepgmr"},
        {"deepgmr_small", "deepgmr-small"},
        {"deepgmr_orig", "deepgmr-orig"},
    };
    for (const auto& [label, config] : deepgmr_cases) {
        Configure(benchmark::RegisterBenchmark(("BM_DeepGmrForward/" + std::string(label)).c_str(),
                                               BM_DeepGmrForward, std::string(config)));
    }
    return true;
}();

}  // namespace
}  // namespace regbench::bench
