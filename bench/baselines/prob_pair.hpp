#pragma once
// The synthetic pair the probabilistic-method benchmarks share.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <string>

#include "core/metrics.hpp"
#include "core/registration.hpp"
#include "core/rng.hpp"
#include "core/synthetic_shapes.hpp"
#include "core/transform.hpp"

namespace regbench {

struct BenchPair {
    PointCloud source, target;
    Transform T_gt;
};

/// Two independent samplings of SmoothBlobSurface with `points` points each (so sigma^2 does
/// not collapse to 0 as on identical samples); target = R(30 deg about (1,1,1)) Y + t.
inline BenchPair MakeBenchPair(Eigen::Index points, std::uint64_t seed = 717) {
    auto rng = MakePairRng(seed, static_cast<std::uint64_t>(points));
    BenchPair p;
    p.source = SmoothBlobSurface(rng, points);
    p.T_gt =
        MakeTransform(RotationFromAxisAngle({1, 1, 1}, 30.0 * M_PI / 180.0), {0.1, -0.05, 0.2});
    p.target = Apply(p.T_gt, SmoothBlobSurface(rng, points));
    return p;
}

/// Sets counters iterations, rre_deg, rte and ok from the last timed result.
inline void ReportAlign(benchmark::State& state, const BenchPair& pair, const AlignResult& r) {
    Transform T = r.T_target_source;
    T.topLeftCorner<3, 3>() /= r.scale;
    const PairMetrics m = MotionMetrics(pair.T_gt, T);
    state.counters["iterations"] = r.iterations;
    state.counters["rre_deg"] = m.rre;
    state.counters["rte"] = m.rte;
    state.counters["ok"] = r.status == AlignStatus::kOk ? 1 : 0;
}

/// The timed loop of the probabilistic-method benchmarks: aligns `pair` with `method` on
/// state.range(1) OpenMP threads (restored afterwards), sets ReportAlign's counters and returns
/// the last result.
inline AlignResult TimeAlign(benchmark::State& state, RegistrationMethod& method,
                             const BenchPair& pair) {
    const int threads = static_cast<int>(state.range(1));
    const int saved = omp_get_max_threads();
    omp_set_num_threads(threads);
    AlignResult r;
    for (auto _ : state) {
        r = method.Align(pair.source, pair.target);
        benchmark::DoNotOptimize(r);
    }
    omp_set_num_threads(saved);
    ReportAlign(state, pair, r);
    return r;
}

}  // namespace regbench
