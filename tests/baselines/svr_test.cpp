#include "baselines/svr.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/math_constants.hpp"
#include "core/transform.hpp"
#include "gmm/gmm_common.hpp"
#include "runners/registry.hpp"
#include "tests/baselines/registration_fixtures.hpp"
#include "tests/testing/method_params.hpp"
#include "tests/testing/shapes.hpp"

namespace regbench {
namespace {

using namespace testing;  // the shared fixtures and checks (tests/testing,
                          // registration_fixtures.hpp)

constexpr int kPoints = 717;
constexpr double kEulerTolRad = 0.1;  // probreg's own SVR test tolerance

void ExpectEulerWithin(const Transform& est, const Transform& gt, double tol_rad) {
    const Eigen::Vector3d e = EulerZyxDegFromRotation(est.topLeftCorner<3, 3>());
    const Eigen::Vector3d g = EulerZyxDegFromRotation(gt.topLeftCorner<3, 3>());
    for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(e[k] - g[k]) * kDegToRad, tol_rad) << k;
}

TEST(OneClassSvm, DualSatisfiesTheNuSvmConstraintsAndKkt) {
    const PointCloud X = LumpyEllipsoid(kPoints, 11);
    const double sigma = EstimateSigmaFromCovariance(X);
    const double gamma = 1.0 / (2.0 * sigma * sigma);
    const double nu = 0.1, tol = 1e-3;
    const OneClassSvm svm = FitOneClassSvm(X, nu, gamma, tol);
    EXPECT_NEAR(svm.alpha.sum(), nu * kPoints, 1e-9);
    EXPECT_GE(svm.alpha.minCoeff(), 0.0);
    EXPECT_LE(svm.alpha.maxCoeff(), 1.0);
    EXPECT_GE(static_cast<double>(svm.support.size()), nu * kPoints);
    // KKT (libsvm's stopping rule, eps = tol): with G_i = sum_j alpha_j K_ij,
    // alpha_i = 0 -> G_i >= rho, alpha_i = 1 -> G_i <= rho, else G_i = rho.
    Eigen::VectorXd alpha_all = Eigen::VectorXd::Zero(kPoints);
    for (size_t s = 0; s < svm.support.size(); ++s) alpha_all[svm.support[s]] = svm.alpha[s];
    for (int i = 0; i < kPoints; ++i) {
        double G = 0.0;
        for (size_t s = 0; s < svm.support.size(); ++s) {
            const double d2 = (X.row(i) - X.row(svm.support[s])).squaredNorm();
            G += svm.alpha[s] * std::exp(-gamma * d2);
        }
        if (alpha_all[i] <= 0.0) {
            EXPECT_GE(G, svm.rho - tol) << i;
        } else if (alpha_all[i] >= 1.0) {
            EXPECT_LE(G, svm.rho + tol) << i;
        } else {
            EXPECT_NEAR(G, svm.rho, tol) << i;
        }
    }
}

TEST(OneClassSvm, RejectsBadNu) {
    const PointCloud X = LumpyEllipsoid(20, 1);
    EXPECT_THROW(FitOneClassSvm(X, 0.0, 1.0, 1e-3), std::invalid_argument);
    EXPECT_THROW(FitOneClassSvm(X, 1.5, 1.0, 1e-3), std::invalid_argument);
}

TEST(Svr, DefaultsRecoverThirtyDegreesAboutZ) {
    const PointCloud Y = LumpyEllipsoid(kPoints, 12);
    const Transform T = ThirtyDegreesAboutZ();
    const AlignResult r = AlignWith("svr", {}, Y, Apply(T, Y));
    ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
    ExpectEulerWithin(r.T_target_source, T, kEulerTolRad);
    EXPECT_GT(r.iterations, 0);
    EXPECT_GE(r.extra.at("support_vectors_source").get<double>(), 0.1 * kPoints);
}

TEST(Svr, ProbregEulerTestAnglesInZeroTo45Degrees) {
    // probreg's test: Euler angles U[0, 45 deg]^3, t = 0; tolerance 0.1 rad, t within 1e-2.
    const PointCloud Y = LumpyEllipsoid(kPoints, 13);
    const Transform T =
        MakeTransform(RotationFromEulerZyxDeg(37.0, 12.0, 25.0), Eigen::Vector3d::Zero());
    const AlignResult r = AlignWith("svr", {}, Y, Apply(T, Y));
    ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
    ExpectEulerWithin(r.T_target_source, T, kEulerTolRad);
    EXPECT_LT(TranslationError(r.T_target_source, T), 1e-2);
}

TEST(Svr, OuterScheduleRunsInBothModes) {
    const PointCloud Y = LumpyEllipsoid(300, 15);
    const Transform T = ThirtyDegreesAboutZ();
    for (const char* compat : {"probreg", "none"}) {
        const AlignResult r =
            AlignWith("svr", {{"compat", compat}, {"outer_iterations", 3}, {"outer_tol", 0.0}}, Y,
                      Apply(T, Y));
        ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
        EXPECT_EQ(r.extra.at("outer_iterations").get<int>(), 3) << compat;
        EXPECT_TRUE(r.T_target_source.allFinite());
    }
}

TEST(Svr, RejectsBadParametersByName) {
    testing::ExpectEachRejected("svr", nlohmann::json::parse(R"({
        "nu": [0.0, 1.2], "gamma": [-1.0], "delta": [0.0], "svm_tol": [0.0],
        "gradient": ["half"], "outer_iterations": [0], "opt_maxiter": [5]
    })"));
}

}  // namespace
}  // namespace regbench
