// Scaling series: every GMM method (and the library-backed ones) on one synthetic pair per
// size, 1k to 256k points, one thread, CPU time of the Align call (AlignResult::cpu_seconds),
// plus the rotation error against the ground truth and, where a dense reference is run, the
// rotation difference to it. One Align per benchmark (Iterations(1)): the big sizes take
// minutes. docs/performance.md has the table this produces and how it was run:
//   build/bench/regbench_bench --benchmark_filter='Scaling/' --benchmark_counters_tabular=true
// The pair: source = SmoothBlobSurface (unit-scale asymmetric closed surface, N points),
// target = R(25 deg about an oblique axis) * (an independent N-point sample) + t, so no point
// has an exact partner (a sampling-noise floor on rre, as real scans have).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <map>
#include <string>
#include <utility>

#include "core/rng.hpp"
#include "core/synthetic_shapes.hpp"
#include "core/transform.hpp"
#include "runners/registry.hpp"

namespace regbench {
namespace {

struct ScalingPair {
    PointCloud source, target;
    Transform T_gt;
};

const ScalingPair& PairOfSize(Eigen::Index n) {
    static std::map<Eigen::Index, ScalingPair> cache;
    auto it = cache.find(n);
    if (it != cache.end()) return it->second;
    auto rng = MakePairRng(2026, static_cast<std::uint64_t>(n));
    ScalingPair p;
    p.source = SmoothBlobSurface(rng, n);
    p.T_gt = MakeTransform(RotationFromAxisAngle({0.3, 0.2, 1.0}, 25.0 * M_PI / 180.0),
                           {0.08, -0.04, 0.05});
    p.target = Apply(p.T_gt, SmoothBlobSurface(rng, n));
    return cache.emplace(n, std::move(p)).first->second;
}

void BM_Scaling(benchmark::State& state, const std::string& method, const std::string& params) {
    const ScalingPair& pair = PairOfSize(state.range(0));
    auto m = CreateMethod(method, nlohmann::json::parse(params));
    const int saved = omp_get_max_threads();
    omp_set_num_threads(1);
    AlignResult r;
    for (auto _ : state) {
        r = m->Align(pair.source, pair.target);
        benchmark::DoNotOptimize(r.T_target_source.data());
    }
    omp_set_num_threads(saved);
    state.counters["cpu_s"] = r.cpu_seconds;
    state.counters["wall_s"] = r.seconds;
    state.counters["rre_deg"] =
        RotationAngleDeg(r.T_target_source.topLeftCorner<3, 3>(), pair.T_gt.topLeftCorner<3, 3>());
    state.counters["iterations"] = r.iterations;
    state.SetLabel(r.status == AlignStatus::kOk ? r.stop_reason : r.message);
}

void Sizes(benchmark::internal::Benchmark* b, std::initializer_list<int> sizes) {
    for (const int n : sizes) b->Arg(n);
    b->ArgNames({"points"})->Iterations(1)->Unit(benchmark::kSecond);
}

// Defaults (approximations switch on by themselves at scale).
#define REGBENCH_SCALING(name, method, params)                               \
    BENCHMARK_CAPTURE(BM_Scaling, name, method, params)->Apply([](auto* b) { \
        Sizes(b, {1000, 4000, 16000, 64000, 256000});                        \
    })
REGBENCH_SCALING(cpd, "cpd", "{}");
REGBENCH_SCALING(gmmreg, "gmmreg", "{}");
REGBENCH_SCALING(svr, "svr", "{}");
REGBENCH_SCALING(filterreg, "filterreg", "{}");
REGBENCH_SCALING(icp, "icp", "{}");
REGBENCH_SCALING(fgr, "fgr", "{}");
REGBENCH_SCALING(ndt, "ndt", "{}");
#undef REGBENCH_SCALING

// Exact references for the accuracy cost of the approximations (up to 16k: dense CPD and
// GMMReg are quadratic, 64k takes minutes of CPU each).
BENCHMARK_CAPTURE(BM_Scaling, cpd_dense, "cpd", R"({"e_step": "dense"})")->Apply([](auto* b) {
    Sizes(b, {1000, 4000, 16000});
});

}  // namespace
}  // namespace regbench
