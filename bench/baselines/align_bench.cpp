// BM_Align: one registration of the bench pair per iteration, for every registered method.
// Benchmarks are registered from AllMethods(), so new methods are timed without edits here.
#include <benchmark/benchmark.h>

#include <exception>
#include <string>

#include "bench/bench_pair.hpp"
#include "core/metrics.hpp"
#include "core/threads.hpp"
#include "runners/registry.hpp"

namespace regbench::bench {
namespace {

/// Thread counts timed for every method; single-threaded is the reported number.
constexpr int kThreadCounts[] = {1, 2};

void BM_Align(benchmark::State& state, const std::string& method_name) {
    const Pair& pair = GetBenchPair().pair;
    SetOmpThreads(static_cast<int>(state.range(1)));  // also covers Open3D, see threads.hpp
    const auto method = CreateMethod(method_name);
    AlignResult result = method->Align(pair.source, pair.target);  // warm-up, untimed
    if (result.status != AlignStatus::kOk) {
        state.SkipWithError(result.message.c_str());
        return;
    }
    for (auto _ : state) {
        result = method->Align(pair.source, pair.target);
        benchmark::DoNotOptimize(result.T_target_source.data());
    }
    state.counters["iterations"] = result.iterations;
    state.counters["rre_deg"] = MotionMetrics(pair.T_gt, result.T_target_source).rre;
    state.counters["ok"] = result.status == AlignStatus::kOk ? 1.0 : 0.0;
}

void BM_AlignUnavailable(benchmark::State& state, const std::string& why) {
    for (auto _ : state) {
    }
    state.SkipWithError(why.c_str());
}

bool RegisterAlignBenchmarks() {
    try {
        const BenchPair& bench_pair = GetBenchPair();
        benchmark::AddCustomContext("bench_pair", bench_pair.origin);
        const auto points = static_cast<int64_t>(bench_pair.pair.source.rows());
        for (const auto& info : AllMethods()) {
            auto* b = benchmark::RegisterBenchmark(("BM_Align/" + info.name).c_str(), BM_Align,
                                                   info.name);
            for (const int threads : kThreadCounts) b->Args({points, threads});
            b->ArgNames({"points", "threads"})->Unit(benchmark::kMillisecond);
        }
    } catch (const std::exception& e) {
        // A bad REGBENCH_BENCH_PAIRS must not abort static initialisation: report it instead.
        benchmark::RegisterBenchmark("BM_Align/unavailable", BM_AlignUnavailable,
                                     std::string(e.what()));
    }
    return true;
}

// Runs before main(), like the BENCHMARK macros (this file is linked into the executable
// directly, not through a static library, so the initialiser is kept).
const bool kAlignBenchmarksRegistered = RegisterAlignBenchmarks();

}  // namespace
}  // namespace regbench::bench
