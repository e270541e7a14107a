#include "baselines/gmmreg.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <limits>

#include "core/math_constants.hpp"
#include "core/transform.hpp"
#include "runners/registry.hpp"
#include "tests/baselines/registration_fixtures.hpp"
#include "tests/testing/method_params.hpp"
#include "tests/testing/shapes.hpp"

namespace regbench {
namespace {

using namespace testing;  // the shared fixtures and checks (tests/testing,
                          // registration_fixtures.hpp)

constexpr int kPoints = 717;
constexpr double kRotTolDeg = 1.0;
constexpr double kTransTol = 0.01;

TEST(GmmReg, ProbregModeRecoversThirtyDegreesAboutZ) {
    const PointCloud Y = LumpyEllipsoid(kPoints, 1);
    const Transform T = ThirtyDegreesAboutZ();
    const AlignResult r = AlignWith("gmmreg", {{"compat", "probreg"}}, Y, Apply(T, Y));
    ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
    EXPECT_LT(RotationErrorDeg(r.T_target_source, T), kRotTolDeg);
    EXPECT_GT(r.iterations, 0);
    EXPECT_FALSE(r.stop_reason.empty());
    EXPECT_LT(r.extra.at("objective").get<double>(), 0.0);
    EXPECT_EQ(r.extra.at("components_source").get<int>(), 573);  // min(800, floor(0.8 * 717))
}

TEST(GmmReg, ProbregModeOnACleanCompletePair) {
    const PointCloud Y = LumpyEllipsoid(kPoints, 2);
    const Transform T = MakeTransform(RotationFromAxisAngle(Eigen::Vector3d(1, 1, 0), kPi / 6),
                                      Eigen::Vector3d(0.2, 0.1, -0.1));
    const AlignResult r = AlignWith("gmmreg", {}, Y, Apply(T, Y));
    ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
    EXPECT_LT(RotationErrorDeg(r.T_target_source, T), kRotTolDeg);
    EXPECT_LT(TranslationError(r.T_target_source, T), kTransTol);
}

TEST(GmmReg, SameSeedSameResultAndThreadCountInvariant) {
    const PointCloud Y = LumpyEllipsoid(kPoints, 4);
    const PointCloud X = Apply(ThirtyDegreesAboutZ(), Y);
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    const AlignResult a = AlignWith("gmmreg", {{"seed", 5}, {"compat", "probreg"}}, Y, X);
    omp_set_num_threads(2);
    const AlignResult b = AlignWith("gmmreg", {{"seed", 5}, {"compat", "probreg"}}, Y, X);
    omp_set_num_threads(threads);
    ASSERT_EQ(a.status, AlignStatus::kOk);
    EXPECT_LT((a.T_target_source - b.T_target_source).cwiseAbs().maxCoeff(), 1e-9);
    const AlignResult c = AlignWith("gmmreg", {{"seed", 6}, {"compat", "probreg"}}, Y, X);
    EXPECT_NE((a.T_target_source - c.T_target_source).cwiseAbs().maxCoeff(), 0.0);
}

TEST(GmmReg, PointFeaturesAndScheduleWork) {
    const PointCloud Y = LumpyEllipsoid(400, 5);
    const Transform T = ThirtyDegreesAboutZ();
    const AlignResult r =
        AlignWith("gmmreg", {{"gmm", "points"}, {"gradient", "exact"}, {"outer_iterations", 3}}, Y,
                  Apply(T, Y));
    ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
    EXPECT_LT(RotationErrorDeg(r.T_target_source, T), kRotTolDeg);
    EXPECT_EQ(r.extra.at("components_source").get<int>(), 400);
    EXPECT_GE(r.extra.at("outer_iterations").get<int>(), 2);
}

TEST(GmmReg, RejectsBadParametersByName) {
    // "sigma2" is no gmmreg parameter (gmmreg's scale is "sigma").
    testing::ExpectEachRejected("gmmreg", nlohmann::json::parse(R"({
        "delta": [1.5], "sigma": [-1.0], "gmm": ["kmeans"], "gradient": ["double"],
        "compat": ["matlab"], "n_gmm_components": [0], "maxiter": [-1], "sigma2": [1.0]
    })"));
}

TEST(GmmReg, ParamsReportResolvedCompatDefaults) {
    const nlohmann::json p = CreateMethod("gmmreg", {{"compat", "none"}})->Params();
    EXPECT_EQ(p.at("gmm"), "points");
    EXPECT_EQ(p.at("gradient"), "exact");
    const nlohmann::json q =
        CreateMethod("gmmreg", {{"compat", "none"}, {"gmm", "sklearn"}})->Params();
    EXPECT_EQ(q.at("gmm"), "sklearn");
}

}  // namespace
}  // namespace regbench
