// Learned networks against their multiply-accumulate floor (docs/performance.md, section 4).
// BM_OgmmForward / BM_DeepGmrForward: one batch-1 forward (no gradient, eval mode) per
// iteration, for the named configs and OGMM's full-attention variant (paper Tab. 6 "c" vs "f").
// BM_RienetForward: RIENet (networks/families/rienet/net.hpp, the authors' ModelNet40 config), the
// same way; its MACs from RienetForwardMacs. BM_OmnetForward: OMNet
// (networks/families/omnet/net.hpp) at the authors' widths and omnet-small's. BM_RgmForward: RGM
// (networks/families/rgm/net.hpp) at the authors' widths and rgm-small's, the whole test-time
// pipeline (four matches, their assignments and SVDs); BM_RgmAssignment: the assignment alone on a
// points x points matrix (not in the MACs: the part of the pipeline the GEMM floor does not bound).
// BM_RegtrForward: REGTR (networks/families/regtr/net.hpp) with the authors' ModelNet config and
// regtr-small's. BM_ShippedForward/rgm_small, /regtr_small: the shipped checkpoints
// (data/models/rgm, data/models/regtr, what `reproduce` runs) on the same pair; with untrained
// weights RGM's correspondences are near uniform and its assignment (no MACs) slow, with the
// shipped ones as in a run (docs/performance.md, "RGM against its floor"). BM_OgmmTrainStep /
// BM_DeepGmrTrainStep: one training step (train mode: forward, loss, backward, Adam) on a batch of
// 8 pairs, the shipped recipes' batch. Network only: no ICP (the methods' time, ICP included, is
// BM_Align/ogmm, BM_Align/deepgmr). Counters, all in CPU time of the calling thread (one torch
// thread):
//   MACs       analytic multiply-accumulates of the timed work (networks/cost.hpp; a training step
//              counts forward + backward as 3 x the forward, the usual convention)
//   GMAC_per_s rate of a 717x512 by 512x512 fp32 torch::mm, timed interleaved with the network
//              in the same process, so a loaded machine slows both alike
//   floor_ms   MACs at that rate
//   ratio      CPU ms of the network / floor_ms (targets: forward 2.5, training step 4)
// Run: OMP_WAIT_POLICY=PASSIVE build/bench/regbench_bench --benchmark_filter='Forward|TrainStep'
#include <benchmark/benchmark.h>

#include <string>
#include <utility>

#include "core/cpu_time.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/cost.hpp"
#include "networks/families/ogmm/net.hpp"
#include "networks/families/rgm/assignment.hpp"
#include "networks/families/rienet/net.hpp"
#include "networks/zoo.hpp"

namespace regbench::bench {
namespace {

constexpr int64_t kGemmRows = 717, kGemmInner = 512, kGemmCols = 512;
constexpr int64_t kTrainBatch = 8;

/// A uniform random batch of `batch` pairs of `points` points in [-0.5, 0.5]^3 with the ground
/// truth and overlap labels a loss needs.
networks::PairBatch RandomBatch(int64_t batch, int64_t points) {
    torch::manual_seed(0);
    networks::PairBatch pair;
    pair.source = torch::rand({batch, points, 3}) - 0.5;
    pair.target = torch::rand({batch, points, 3}) - 0.5;
    pair.T_gt = torch::eye(4).expand({batch, 4, 4}).contiguous();
    pair.source_overlap = (torch::rand({batch, points}) > 0.3).to(torch::kFloat);
    pair.target_overlap = (torch::rand({batch, points}) > 0.3).to(torch::kFloat);
    return pair;
}

/// Times `work` and, interleaved, the GEMM floor; sets the counters.
template <typename Work>
void TimeAgainstGemm(benchmark::State& state, double macs, Work&& work) {
    const torch::Tensor a = torch::rand({kGemmRows, kGemmInner});
    const torch::Tensor b = torch::rand({kGemmInner, kGemmCols});
    torch::Tensor c = torch::empty({kGemmRows, kGemmCols});
    work();  // warm-up, untimed
    torch::mm_out(c, a, b);
    double work_cpu = 0.0, gemm_cpu = 0.0;
    int64_t gemms = 0;
    for (auto _ : state) {
        const double t0 = ThreadCpuSeconds();
        work();
        const double t1 = ThreadCpuSeconds();
        work_cpu += t1 - t0;
        // About as much GEMM time as network time, at least one GEMM.
        double spent = 0.0;
        do {
            torch::mm_out(c, a, b);
            ++gemms;
            spent = ThreadCpuSeconds() - t1;
        } while (spent < 0.25 * (t1 - t0));
        gemm_cpu += spent;
        benchmark::DoNotOptimize(c.data_ptr());
    }
    const double gemm_rate =
        static_cast<double>(gemms * kGemmRows * kGemmInner * kGemmCols) / gemm_cpu;
    const double work_ms = 1e3 * work_cpu / static_cast<double>(state.iterations());
    const double floor_ms = 1e3 * macs / gemm_rate;
    state.counters["MACs"] = macs;
    state.counters["GMAC_per_s"] = gemm_rate * 1e-9;
    state.counters["floor_ms"] = floor_ms;
    state.counters["cpu_ms"] = work_ms;
    state.counters["ratio"] = work_ms / floor_ms;
}

/// Forward of one pair of state.range(0) points.
void TimeForward(benchmark::State& state, networks::RegistrationNet& net,
                 const nlohmann::json& config) {
    net.eval();
    const int64_t points = state.range(0);
    const networks::PairBatch pair = RandomBatch(1, points);
    torch::NoGradGuard no_grad;
    const auto macs =
        static_cast<double>(networks::ComputeForwardCost(config, points, points).total);
    TimeAgainstGemm(state, macs, [&] {
        torch::manual_seed(1);  // same FPS starts every iteration
        const networks::NetOutput out = net.Forward(pair);
        benchmark::DoNotOptimize(out.T.data_ptr());
    });
    state.counters["parameters"] = static_cast<double>(networks::CountParameters(net));
}

/// One training step (train mode, Adam) on kTrainBatch pairs of state.range(0) points.
void TimeTrainStep(benchmark::State& state, networks::RegistrationNet& net,
                   const nlohmann::json& config) {
    net.train();
    const int64_t points = state.range(0);
    const networks::PairBatch batch = RandomBatch(kTrainBatch, points);
    torch::optim::Adam opt(net.parameters(), torch::optim::AdamOptions(1e-4));
    const double forward_macs =
        static_cast<double>(networks::ComputeForwardCost(config, points, points).total);
    TimeAgainstGemm(state, 3.0 * forward_macs * kTrainBatch, [&] {
        torch::manual_seed(1);
        const networks::NetOutput out = net.Forward(batch);
        const torch::Tensor loss = net.Loss(batch, out).at("total");
        opt.zero_grad();
        loss.backward();
        opt.step();
    });
}

nlohmann::json OgmmConfig(const std::string& name, const std::string& attention) {
    nlohmann::json config = networks::OgmmNamedConfig(name);
    config["attention"] = attention;
    return config;
}

void BM_OgmmForward(benchmark::State& state, const std::string& name,
                    const std::string& attention) {
    torch::set_num_threads(static_cast<int>(state.range(1)));
    const nlohmann::json config = OgmmConfig(name, attention);
    TimeForward(state, *networks::MakeOgmmNet(config), config);
}

/// A zoo model's forward (DeepGMR, OMNet: any family whose config NamedConfig knows).
void BM_ZooForward(benchmark::State& state, const std::string& name) {
    torch::set_num_threads(static_cast<int>(state.range(1)));
    const nlohmann::json config = networks::NamedConfig(name);
    TimeForward(state, *networks::MakeNetFromConfig(config), config);
}

/// A shipped checkpoint's forward (data/models/<dir>, the weights `reproduce` runs), on the same
/// uniform pair: the trained weights make the data-dependent work (RGM's assignment) what it is
/// in a run, where the untrained ones make it near uniform and slow.
void BM_ShippedForward(benchmark::State& state, const std::string& dir) {
    torch::set_num_threads(static_cast<int>(state.range(1)));
    const std::string path = std::string(REGBENCH_SOURCE_DIR) + "/data/models/" + dir;
    const nlohmann::json config = networks::CheckpointNetConfig(path);
    TimeForward(state, *networks::LoadNetFromCheckpoint(path), config);
}

void BM_RienetForward(benchmark::State& state) {
    torch::set_num_threads(static_cast<int>(state.range(1)));
    const networks::RienetConfig config;
    networks::RienetNet net{config};
    net.eval();
    const int64_t points = state.range(0);
    const networks::PairBatch pair = RandomBatch(1, points);
    torch::NoGradGuard no_grad;
    const auto macs =
        static_cast<double>(networks::RienetForwardMacs(config, points, points).at("total"));
    TimeAgainstGemm(state, macs, [&] {
        const networks::NetOutput out = net.Forward(pair);
        benchmark::DoNotOptimize(out.T.data_ptr());
    });
    state.counters["parameters"] = static_cast<double>(networks::CountParameters(net));
}

void BM_RgmAssignment(benchmark::State& state) {
    const int64_t points = state.range(0);
    torch::manual_seed(0);
    const torch::Tensor w = torch::rand({points, points}, torch::kDouble).contiguous();
    const std::vector<double> weights(w.data_ptr<double>(), w.data_ptr<double>() + w.numel());
    for (auto _ : state) {
        benchmark::DoNotOptimize(networks::MaxWeightAssignment(weights, points, points));
    }
}

void BM_OgmmTrainStep(benchmark::State& state, const std::string& name) {
    torch::set_num_threads(static_cast<int>(state.range(1)));
    const nlohmann::json config = OgmmConfig(name, "clustered");
    TimeTrainStep(state, *networks::MakeOgmmNet(config), config);
}

void BM_DeepGmrTrainStep(benchmark::State& state, const std::string& name) {
    torch::set_num_threads(static_cast<int>(state.range(1)));
    const nlohmann::json config = networks::NamedConfig(name);
    TimeTrainStep(state, *networks::MakeNetFromConfig(config), config);
}

/// 717 points (the bench pair's size) on one thread, in milliseconds.
void Configure(benchmark::internal::Benchmark* b) {
    b->Args({717, 1})->ArgNames({"points", "threads"})->Unit(benchmark::kMillisecond);
}

// Runs before main(), like the BENCHMARK macros (see align_bench.cpp). Names as
// BM_OgmmForward/<label>, BM_DeepGmrForward/<label>, BM_*TrainStep/<label>.
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
                                               BM_ZooForward, std::string(config)));
    }
    // OMNet: the authors' widths (53.7 M parameters) and the shipped omnet-small (width / 4).
    for (const auto& [label, config] :
         {std::pair{"omnet", "omnet"}, {"omnet_small", "omnet-small"}}) {
        Configure(benchmark::RegisterBenchmark(("BM_OmnetForward/" + std::string(label)).c_str(),
                                               BM_ZooForward, std::string(config)));
    }
    Configure(benchmark::RegisterBenchmark("BM_RienetForward/rienet", BM_RienetForward));
    // RGM: the authors' widths (25.0 M parameters) and rgm-small (width / 8).
    for (const auto& [label, config] : {std::pair{"rgm", "rgm"}, {"rgm_small", "rgm-small"}}) {
        Configure(benchmark::RegisterBenchmark(("BM_RgmForward/" + std::string(label)).c_str(),
                                               BM_ZooForward, std::string(config)));
    }
    Configure(benchmark::RegisterBenchmark("BM_RgmAssignment", BM_RgmAssignment));
    // The shipped rgm-small and regtr-small checkpoints (data/models/rgm, data/models/regtr).
    for (const auto& [label, dir] : {std::pair{"BM_ShippedForward/rgm_small", "rgm"},
                                     {"BM_ShippedForward/regtr_small", "regtr"}}) {
        Configure(benchmark::RegisterBenchmark(label, BM_ShippedForward, std::string(dir)));
    }
    // REGTR: the authors' ModelNet model (11.5 M parameters) and the shipped regtr-small.
    for (const auto& [label, config] :
         {std::pair{"regtr", "regtr"}, {"regtr_small", "regtr-small"}}) {
        Configure(benchmark::RegisterBenchmark(("BM_RegtrForward/" + std::string(label)).c_str(),
                                               BM_ZooForward, std::string(config)));
    }
    Configure(benchmark::RegisterBenchmark("BM_OgmmTrainStep/ogmm_small", BM_OgmmTrainStep,
                                           std::string("ogmm-small")));
    Configure(benchmark::RegisterBenchmark("BM_DeepGmrTrainStep/deepgmr_small", BM_DeepGmrTrainStep,
                                           std::string("deepgmr-small")));
    return true;
}();

}  // namespace
}  // namespace regbench::bench
