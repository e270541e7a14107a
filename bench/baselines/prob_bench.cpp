// BM_ProbAlign: every registered probabilistic method (cpd, gmmreg, svr, filterreg) on a
// synthetic smooth-surface pair of 717, 2048 and 10000 points, 1 and 2 OpenMP threads.
// The pair is built before the timed loop; counters iterations and rre_deg prove the timed
// run was right.
#include <benchmark/benchmark.h>

#include "bench/baselines/prob_pair.hpp"
#include "runners/registry.hpp"

namespace regbench {
namespace {

void BM_ProbAlign(benchmark::State& state, const std::string& method_name) {
    const BenchPair pair = MakeBenchPair(static_cast<Eigen::Index>(state.range(0)));
    auto method = CreateMethod(method_name);
    TimeAlign(state, *method, pair);
}

/// Registers BM_ProbAlign/<method> for each probabilistic method present in the registry.
const bool kRegistered = [] {
    for (const char* name : {"cpd", "gmmreg", "svr", "filterreg"}) {
        bool known = false;
        for (const auto& m : AllMethods()) known = known || m.name == name;
        if (!known) continue;
        benchmark::RegisterBenchmark((std::string("BM_ProbAlign/") + name).c_str(), BM_ProbAlign,
                                     std::string(name))
            ->ArgsProduct({{717, 2048, 10000}, {1, 2}})
            ->ArgNames({"points", "threads"})
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
    }
    return true;
}();

}  // namespace
}  // namespace regbench
