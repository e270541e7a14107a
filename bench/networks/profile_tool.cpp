// regbench_networks_profile: where a learned network's time goes, by operation and by stage.
// Runs one named config's forward (eval mode, no gradient) or training step (train mode,
// forward + loss + backward + Adam) on a uniform random pair under LibTorch's profiler and
// prints, per name, the calls and the self CPU time (time inside the op minus the ops it called)
// and the inclusive time. Stages are the `ogmm::...` / `deepgmr::...` scopes the networks open
// (networks/layers/profile_scope.hpp); aten::... rows are LibTorch operators.
// Usage: regbench_networks_profile CONFIG [forward|train|forward-time|train-time] [repetitions]
//                              [points] [batch]
//   e.g. OMP_WAIT_POLICY=PASSIVE build/bench/regbench_networks_profile ogmm-small train 3
// The *-time modes run without the profiler (whose per-op cost favours graphs of fewer ops) and
// print, like bench/ogmm's BM_*TrainStep, the CPU seconds of the calling thread per repetition,
// the GEMM floor (networks/cost MACs, 3x the forward's for a training step, at the rate of a
// 717x512x512 fp32 torch::mm timed interleaved with the work, about 1 GEMM second per 4 work
// seconds), the ratio to it, pairs per CPU second and the minor page faults per repetition.
#include <sys/resource.h>
#include <torch/csrc/autograd/profiler_legacy.h>
#include <torch/torch.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "core/cpu_time.hpp"
#include "core/memory_policy.hpp"
#include "networks/cost.hpp"
#include "networks/net.hpp"
#include "networks/training/train.hpp"
#include "networks/zoo.hpp"

namespace {

namespace profiler = torch::autograd::profiler;

struct Totals {
    long calls = 0;
    double self_us = 0.0;
    double total_us = 0.0;
};

/// Self and inclusive times per name from the push/pop events of every thread.
std::map<std::string, Totals> Aggregate(const profiler::thread_event_lists& threads) {
    std::map<std::string, Totals> out;
    for (const auto& events : threads) {
        struct Open {
            const profiler::LegacyEvent* push;
            double children_us;
        };
        std::vector<Open> stack;
        for (const auto& e : events) {
            if (e.kindStr() == "push") {
                stack.push_back({&e, 0.0});
            } else if (e.kindStr() == "pop" && !stack.empty()) {
                const Open open = stack.back();
                stack.pop_back();
                const double elapsed = open.push->cpuElapsedUs(e);
                Totals& t = out[open.push->name()];
                ++t.calls;
                t.total_us += elapsed;
                t.self_us += elapsed - open.children_us;
                if (!stack.empty()) stack.back().children_us += elapsed;
            }
        }
    }
    return out;
}

void Print(const std::map<std::string, Totals>& totals, int repetitions) {
    std::vector<std::pair<std::string, Totals>> rows(totals.begin(), totals.end());
    std::sort(rows.begin(), rows.end(),
              [](const auto& a, const auto& b) { return a.second.self_us > b.second.self_us; });
    double all_self = 0.0;
    for (const auto& [name, t] : rows) all_self += t.self_us;
    std::printf("%-44s %8s %12s %8s %12s\n", "name (per repetition)", "calls", "self ms", "self %",
                "incl. ms");
    for (const auto& [name, t] : rows) {
        if (t.self_us < 0.002 * all_self && name.rfind("ogmm::", 0) != 0 &&
            name.rfind("deepgmr::", 0) != 0) {
            continue;  // rows under 0.2% of the time, stages always shown
        }
        std::printf("%-44s %8.1f %12.3f %7.1f%% %12.3f\n", name.substr(0, 44).c_str(),
                    static_cast<double>(t.calls) / repetitions, t.self_us / 1e3 / repetitions,
                    100.0 * t.self_us / all_self, t.total_us / 1e3 / repetitions);
    }
    std::printf("%-44s %8s %12.3f\n", "all (self times summed)", "", all_self / 1e3 / repetitions);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::cerr << "usage: regbench_networks_profile CONFIG [forward|train|forward-time|train-time]"
                     " [repetitions] [points] [batch]\n";
        return 2;
    }
    const std::string name = argv[1];
    const std::string full_mode = argc > 2 ? argv[2] : "forward";
    const bool timed = full_mode.size() > 5 && full_mode.substr(full_mode.size() - 5) == "-time";
    const std::string mode = timed ? full_mode.substr(0, full_mode.size() - 5) : full_mode;
    const int repetitions = argc > 3 ? std::stoi(argv[3]) : 3;
    const int64_t points = argc > 4 ? std::stoll(argv[4]) : 717;
    const int64_t batch = argc > 5 ? std::stoll(argv[5]) : (mode == "train" ? 8 : 1);
    if (mode != "forward" && mode != "train") {
        std::cerr << "mode must be forward or train, got '" << mode << "'\n";
        return 2;
    }
    torch::set_num_threads(1);
    // Forward and training step run with the allocator setting `regbench` uses; REGBENCH_MALLOC=
    // default keeps glibc's (for A/B runs).
    const char* malloc_mode = std::getenv("REGBENCH_MALLOC");
    const bool retain = !(malloc_mode != nullptr && std::string(malloc_mode) == "default");
    if (retain) regbench::RetainFreedMemory();
    torch::manual_seed(0);
    const nlohmann::json config = regbench::networks::NamedConfig(name);
    const auto net = regbench::networks::MakeNetFromConfig(config);
    regbench::networks::PairBatch pair;
    pair.source = torch::rand({batch, points, 3}) - 0.5;
    pair.target = torch::rand({batch, points, 3}) - 0.5;
    pair.T_gt = torch::eye(4).expand({batch, 4, 4}).contiguous();
    pair.source_overlap = (torch::rand({batch, points}) > 0.3).to(torch::kFloat);
    pair.target_overlap = (torch::rand({batch, points}) > 0.3).to(torch::kFloat);
    torch::optim::Adam opt(net->parameters(), torch::optim::AdamOptions(1e-4));
    const auto run = [&] {
        if (mode == "forward") {
            net->eval();
            torch::NoGradGuard no_grad;
            net->Forward(pair);
            return;
        }
        net->train();
        const auto out = net->Forward(pair);
        const auto loss = net->Loss(pair, out).at("total");
        opt.zero_grad();
        loss.backward();
        opt.step();
    };
    run();  // warm-up, unprofiled
    if (timed) {
        const torch::Tensor a = torch::rand({717, 512}), b = torch::rand({512, 512});
        torch::Tensor c = torch::empty({717, 512});
        torch::mm_out(c, a, b);
        double work = 0.0, gemm = 0.0;
        int64_t gemms = 0;
        rusage before{}, after{};
        long faults = 0;
        for (int i = 0; i < repetitions; ++i) {
            getrusage(RUSAGE_THREAD, &before);
            const double t0 = regbench::ThreadCpuSeconds();
            run();
            const double t1 = regbench::ThreadCpuSeconds();
            getrusage(RUSAGE_THREAD, &after);
            faults += after.ru_minflt - before.ru_minflt;
            work += t1 - t0;
            double spent = 0.0;
            do {
                torch::mm_out(c, a, b);
                ++gemms;
                spent = regbench::ThreadCpuSeconds() - t1;
            } while (spent < 0.25 * (t1 - t0));
            gemm += spent;
        }
        const double rate = static_cast<double>(gemms) * 717.0 * 512.0 * 512.0 / gemm;
        const double forward_macs =
            static_cast<double>(regbench::networks::ComputeForwardCost(config, points, points).total);
        const double macs =
            (mode == "train" ? 3.0 : 1.0) * forward_macs * static_cast<double>(batch);
        const double per = work / repetitions;
        std::printf("%s %s: %lld points, batch %lld, 1 thread, %d repetitions%s\n", name.c_str(),
                    full_mode.c_str(), static_cast<long long>(points),
                    static_cast<long long>(batch), repetitions,
                    retain ? ", freed memory retained (as regbench)" : "");
        std::printf(
            "cpu_s %.4f  GMAC %.3f  GMAC_per_s %.2f  floor_s %.4f  ratio %.3f  "
            "pairs_per_cpu_s %.3f  minflt %.0f\n",
            per, macs * 1e-9, rate * 1e-9, macs / rate, per / (macs / rate),
            static_cast<double>(batch) / per, static_cast<double>(faults) / repetitions);
        return 0;
    }
    profiler::thread_event_lists events;
    {
        profiler::TLSLegacyProfilerGuard guard(
            torch::profiler::impl::ProfilerConfig(torch::profiler::impl::ProfilerState::CPU),
            [&](const profiler::thread_event_lists& e) { events = e; });
        for (int i = 0; i < repetitions; ++i) run();
    }
    std::printf("%s %s: %lld points, batch %lld, 1 thread, %d repetitions\n", name.c_str(),
                mode.c_str(), static_cast<long long>(points), static_cast<long long>(batch),
                repetitions);
    Print(Aggregate(events), repetitions);
    return 0;
}
