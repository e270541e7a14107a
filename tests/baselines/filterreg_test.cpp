#include "baselines/filterreg.hpp"

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "core/metrics.hpp"
#include "core/rng.hpp"
#include "core/transform.hpp"
#include "runners/registry.hpp"
#include "tests/testing/synthetic.hpp"

namespace regbench {
namespace {

PointCloud Ellipsoid(std::mt19937_64& rng, Eigen::Index n) {
    PointCloud p(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        Eigen::Vector3d v(StandardNormal(rng), StandardNormal(rng), StandardNormal(rng));
        v.normalize();
        p.row(i) << 0.9 * v.x(), 0.6 * v.y(), 0.4 * v.z();
    }
    return p;
}

TEST(FilterRegExplore, Independent) {
    for (int seed = 1; seed <= 3; ++seed) {
        for (Eigen::Vector3d axis : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 2, 3)}) {
            const Transform T = MakeTransform(RotationFromAxisAngle(axis, 30 * M_PI / 180), {0.1, -0.05, 0.2});
            const Pair pair = testing::SyntheticPair(717, seed, T);
            for (const char* params : {R"({"update_sigma2":true,"maxiter":200})",R"({"update_sigma2":true,"maxiter":800})",
                                       R"({"estimator":"exact","update_sigma2":true,"maxiter":200})",
                                       R"({"estimator":"exact","update_sigma2":true,"maxiter":800})", R"({"estimator":"exact","update_sigma2":true,"min_sigma2":0.003})"}) {
                auto method = CreateMethod("filterreg", nlohmann::json::parse(params));
                const AlignResult r = method->Align(pair.source, pair.target);
                const PairMetrics pm = MotionMetrics(T, r.T_target_source);
                std::printf("seed %d axis %.0f %-45s it=%2d %-14s rre=%.4f rte=%.5f s2=%.5f used=%d %.2f ms\n", seed, axis.x(), params,
                            r.iterations, r.stop_reason.c_str(), pm.rre, pm.rte, r.extra["sigma2"].get<double>(),
                            r.extra["points_used"].get<int>(), r.seconds * 1e3);
            }
        }
    }
}

TEST(FilterRegExplore, Print) {
    auto rng = MakePairRng(7, 0);
    const PointCloud Y = Ellipsoid(rng, 717);
    for (double deg : {30.0}) {
        const Transform T = MakeTransform(RotationFromAxisAngle({0, 0, 1}, deg * M_PI / 180),
                                          {0.1, -0.05, 0.2});
        const PointCloud X = Apply(T, Y);
        for (const char* params : {"{}", R"({"update_sigma2":true})", R"({"compat":"none"})",
                                   R"({"estimator":"exact"})", R"({"estimator":"exact","update_sigma2":true})",
                                   R"({"objective":"pt2pl"})", R"({"objective":"pt2pl","update_sigma2":true})"}) {
            auto method = CreateMethod("filterreg", nlohmann::json::parse(params));
            const AlignResult r = method->Align(Y, X);
            const PairMetrics pm = MotionMetrics(T, r.T_target_source);
            std::printf("%-50s %s it=%d %s rre=%.4f rte=%.5f %s %.3f ms\n", params, ToString(r.status),
                        r.iterations, r.stop_reason.c_str(), pm.rre, pm.rte, r.extra.dump().c_str(),
                        r.seconds * 1e3);
        }
    }
}

}  // namespace
}  // namespace regbench
