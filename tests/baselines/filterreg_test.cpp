#include "baselines/filterreg.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/math_constants.hpp"
#include "core/metrics.hpp"
#include "core/normals.hpp"
#include "core/rng.hpp"
#include "core/transform.hpp"
#include "gmm/gmm_common.hpp"
#include "runners/registry.hpp"
#include "tests/testing/synthetic.hpp"

namespace regbench {
namespace {

constexpr double kEulerTolRad = 0.2;        // spec test 5/6 and probreg's own test
constexpr double kUpdateSigmaTolDeg = 2.0;  // spec test 5 with update_sigma2
constexpr double kCleanRreTolDeg = 1.0;     // issue: clean complete pair, 30 deg
constexpr double kCleanRteTol = 0.01;
constexpr double kProbregTranslationTol = 1e-2;

Transform SpecMotion() {
    return MakeTransform(RotationFromAxisAngle({0.0, 0.0, 1.0}, 30.0 * kDegToRad),
                         {0.1, -0.05, 0.2});
}

AlignResult RunFilterReg(const std::string& params, const PointCloud& source,
                         const PointCloud& target) {
    auto method = CreateMethod("filterreg", nlohmann::json::parse(params));
    return method->Align(source, target);
}

double MaxEulerErrorRad(const Transform& T_gt, const Transform& T_est) {
    const Eigen::Vector3d a = EulerZyxDegFromRotation(T_gt.topLeftCorner<3, 3>());
    const Eigen::Vector3d b = EulerZyxDegFromRotation(T_est.topLeftCorner<3, 3>());
    return (a - b).cwiseAbs().maxCoeff() * kDegToRad;
}

// ---- E-step ---------------------------------------------------------------------------------

TEST(FilterRegEStep, ExactEstimatorMatchesBruteForceWithinCutoff) {
    const PointCloud Y = testing::EllipsoidSurface(200, 1);
    const PointCloud X = Apply(SpecMotion(), testing::EllipsoidSurface(200, 2));
    const Normals normals = EstimateNormals(X, 10);
    const double sigma2 = 0.02;
    const FilterRegMoments mom =
        FilterRegEStep(Y, X, &normals, sigma2, true, FilterRegEstimator::kExact);
    const double r2 = 9.0 * sigma2;
    for (Eigen::Index i = 0; i < Y.rows(); ++i) {
        double m0 = 0.0, m2 = 0.0;
        Eigen::Vector3d m1 = Eigen::Vector3d::Zero(), nx = Eigen::Vector3d::Zero();
        for (Eigen::Index j = 0; j < X.rows(); ++j) {
            const double d2 = (X.row(j) - Y.row(i)).squaredNorm();
            if (d2 > r2) continue;
            const double k = std::exp(-d2 / (2.0 * sigma2));
            m0 += k;
            m1 += k * X.row(j).transpose();
            m2 += k * X.row(j).squaredNorm();
            nx += k * normals.row(j).transpose();
        }
        EXPECT_NEAR(mom.m0[i], m0, 1e-12);
        EXPECT_NEAR(mom.m2[i], m2, 1e-12);
        EXPECT_LT((mom.m1.row(i).transpose() - m1).norm(), 1e-12);
        EXPECT_LT((mom.nx.row(i).transpose() - nx).norm(), 1e-12);
    }
}

// Spec test 4 (second half): with the blur forced on, the lattice's m1/m0 is within 0.2 sigma
// of the exact Gaussian mean sum_j k_ij x_j / sum_j k_ij.
TEST(FilterRegEStep, BlurredLatticeMeanIsCloseToGaussianMean) {
    const PointCloud Y = testing::EllipsoidSurface(717, 7);
    const PointCloud X = Apply(
        MakeTransform(RotationFromAxisAngle({0, 0, 1}, 30.0 * kDegToRad), Eigen::Vector3d::Zero()),
        Y);
    const double sigma2 = SquaredDistanceMean(Y, X);
    const double sigma = std::sqrt(sigma2);
    const FilterRegMoments auto_blur = FilterRegEStep(Y, X, nullptr, sigma2, false);
    EXPECT_FALSE(auto_blur.blurred);  // > 0.015 N vertices: probreg drops the blur
    const FilterRegMoments mom = FilterRegEStep(Y, X, nullptr, sigma2, false,
                                                FilterRegEstimator::kLattice, LatticeBlur::kOn);
    ASSERT_TRUE(mom.blurred);
    EXPECT_GT(mom.lattice_vertices, 0.015 * 717);
    double worst = 0.0;
    for (Eigen::Index i = 0; i < Y.rows(); ++i) {
        double den = 0.0;
        Eigen::Vector3d num = Eigen::Vector3d::Zero();
        for (Eigen::Index j = 0; j < X.rows(); ++j) {
            const double k = std::exp(-(X.row(j) - Y.row(i)).squaredNorm() / (2.0 * sigma2));
            den += k;
            num += k * X.row(j).transpose();
        }
        const Eigen::Vector3d lattice_mean = mom.m1.row(i).transpose() / mom.m0[i];
        worst = std::max(worst, (lattice_mean - num / den).norm());
    }
    EXPECT_LT(worst, 0.2 * sigma);
}

TEST(FilterRegEStep, UnblurredLatticeLeavesFarPointsWithoutMass) {
    // A source point far from every target gets m0 == 0 (compact tent kernel), the case the
    // M-step drops.
    PointCloud X = testing::EllipsoidSurface(100, 3);
    PointCloud Y(2, 3);
    Y << 0.9, 0.0, 0.0, 50.0, 50.0, 50.0;
    const FilterRegMoments mom = FilterRegEStep(Y, X, nullptr, 0.01, true);
    EXPECT_GT(mom.m0[0], 0.0);
    EXPECT_EQ(mom.m0[1], 0.0);
    EXPECT_EQ(mom.m2.size(), 2);
}

// ---- Registration ---------------------------------------------------------------------------

// Spec test 5: target = R(30 deg about z) Y + (0.1, -0.05, 0.2).
TEST(FilterReg, SpecMotionWithinEulerToleranceWithProbregDefaults) {
    const PointCloud Y = testing::EllipsoidSurface(717, 7);
    const PointCloud X = Apply(SpecMotion(), Y);
    const AlignResult r = RunFilterReg(R"({"compat": "probreg"})", Y, X);
    ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
    EXPECT_LT(MaxEulerErrorRad(SpecMotion(), r.T_target_source), kEulerTolRad);
    EXPECT_EQ(r.extra["blurred_iterations"], 0);  // sigma2 = sqsum: blur is never kept
    // sigma never changes with probreg's defaults.
    EXPECT_NEAR(r.extra["sigma2"].get<double>(), SquaredDistanceMean(Y, X), 1e-12);
}

TEST(FilterReg, SpecMotionWithUpdateSigma2) {
    const PointCloud Y = testing::EllipsoidSurface(717, 7);
    const PointCloud X = Apply(SpecMotion(), Y);
    const AlignResult r = RunFilterReg(R"({"update_sigma2": true})", Y, X);
    ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
    EXPECT_LT(MotionMetrics(SpecMotion(), r.T_target_source).rre, kUpdateSigmaTolDeg);
    EXPECT_LT(r.extra["sigma2"].get<double>(), 0.01);
}

// Spec test 6, probreg's tests/test_filterreg.py: Euler angles U[0, 45 deg]^3 (transforms3d
// 'sxyz': R = Rz(c) Ry(b) Rx(a)), t = 0, target = the moved source itself.
TEST(FilterReg, ProbregOwnTest) {
    const PointCloud Y = testing::BumpyEllipsoid(717, 5);
    auto rng = MakePairRng(606, 0);
    for (int trial = 0; trial < 5; ++trial) {
        const double a = UniformReal(rng, 0.0, 45.0);
        const double b = UniformReal(rng, 0.0, 45.0);
        const double c = UniformReal(rng, 0.0, 45.0);
        const Transform T =
            MakeTransform(RotationFromEulerZyxDeg(c, b, a), Eigen::Vector3d::Zero());
        const AlignResult r = RunFilterReg("{}", Y, Apply(T, Y));
        ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
        EXPECT_LT(MaxEulerErrorRad(T, r.T_target_source), kEulerTolRad) << "trial " << trial;
        const Eigen::Vector3d t = r.T_target_source.topRightCorner<3, 1>();
        EXPECT_LT(t.cwiseAbs().maxCoeff(), kProbregTranslationTol) << "trial " << trial;
    }
}

// The issue's bar for every method: a clean complete pair (target = the moved source, no
// noise) with a 30-degree motion, rre < 1 deg and rte < 0.01. probreg's fixed sigma misses it
// (the tent-kernel mean is biased at sigma ~ 0.5: 2-3 deg); compat "none" (update_sigma2 on)
// passes with either estimator. pt2pl needs a small given sigma2, as in probreg's pt2pl
// example (sigma2 = 0.01): from sqsum its undamped Gauss-Newton steps can flip the cloud.
TEST(FilterReg, CleanCompletePairWithCorrectDefaults) {
    const Transform T =
        MakeTransform(RotationFromAxisAngle({1.0, 2.0, 3.0}, 30.0 * kDegToRad), {0.1, -0.05, 0.2});
    for (std::uint64_t seed : {1, 2, 3}) {
        const PointCloud Y = testing::BumpyEllipsoid(717, seed);
        const PointCloud X = Apply(T, Y);
        for (const char* params :
             {R"({"compat": "none"})", R"({"compat": "none", "estimator": "exact"})",
              R"({"compat": "none", "objective": "pt2pl", "sigma2": 0.01})"}) {
            const AlignResult r = RunFilterReg(params, Y, X);
            ASSERT_EQ(r.status, AlignStatus::kOk) << params << ": " << r.message;
            const PairMetrics m = MotionMetrics(T, r.T_target_source);
            EXPECT_LT(m.rre, kCleanRreTolDeg) << params << " seed " << seed;
            EXPECT_LT(m.rte, kCleanRteTol) << params << " seed " << seed;
        }
        const PairMetrics probreg =
            MotionMetrics(T, RunFilterReg(R"({"compat": "probreg"})", Y, X).T_target_source);
        EXPECT_GT(probreg.rre, kCleanRreTolDeg) << "seed " << seed;  // the documented bias
    }
}

TEST(FilterReg, IdenticalCloudsGiveIdentity) {
    const PointCloud Y = testing::BumpyEllipsoid(500, 9);
    for (const char* params :
         {R"({"compat": "none"})", R"({"compat": "none", "estimator": "exact"})",
          R"({"objective": "pt2pl", "compat": "none", "sigma2": 0.01})"}) {
        const AlignResult r = RunFilterReg(params, Y, Y);
        ASSERT_EQ(r.status, AlignStatus::kOk) << params << ": " << r.message;
        EXPECT_LT((r.T_target_source - Transform::Identity()).cwiseAbs().maxCoeff(), 1e-4)
            << params;
        EXPECT_EQ(r.stop_reason, "converged") << params;
    }
    // probreg's fixed sigma (sqsum): the identity is not its fixed point, because the
    // unblurred lattice's mean m1/m0 is an anisotropic tent average of the target; it stays
    // within a few degrees.
    const AlignResult r = RunFilterReg(R"({"compat": "probreg"})", Y, Y);
    const PairMetrics m = MotionMetrics(Transform::Identity(), r.T_target_source);
    EXPECT_LT(m.rre, 3.0);
    EXPECT_LT(m.rte, 0.03);
}

TEST(FilterReg, ReportsIterationsStopReasonObjectiveAndSigma2) {
    const PointCloud Y = testing::EllipsoidSurface(300, 4);
    const PointCloud X = Apply(SpecMotion(), Y);
    const AlignResult capped =
        RunFilterReg(R"({"maxiter": 2, "tol": 0, "compat": "probreg"})", Y, X);
    EXPECT_EQ(capped.iterations, 2);
    EXPECT_EQ(capped.stop_reason, "max_iterations");
    EXPECT_TRUE(std::isfinite(capped.extra["objective"].get<double>()));
    EXPECT_EQ(capped.extra["sigma2"].get<double>(), SquaredDistanceMean(Y, X));
    const AlignResult given =
        RunFilterReg(R"({"sigma2": 0.05, "maxiter": 3, "compat": "probreg"})", Y, X);
    EXPECT_EQ(given.extra["sigma2"].get<double>(), 0.05);
    const AlignResult floored = RunFilterReg(R"({"sigma2": 1e-6, "maxiter": 1})", Y, Y);
    ASSERT_EQ(floored.iterations, 1);
    EXPECT_EQ(floored.extra["sigma2"].get<double>(), 1e-4);  // min_sigma2 after an iteration
}

TEST(FilterReg, NoOverlapStopsWithPreviousTransform) {
    const PointCloud Y = testing::EllipsoidSurface(200, 5);
    PointCloud X = Y;
    X.rowwise() += Eigen::RowVector3d(100.0, 0.0, 0.0);
    const AlignResult r = RunFilterReg(R"({"sigma2": 0.01})", Y, X);
    ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
    EXPECT_EQ(r.stop_reason, "no_overlap");
    EXPECT_EQ(r.iterations, 0);
    EXPECT_TRUE(r.T_target_source.isApprox(Transform::Identity()));
}

TEST(FilterReg, CompatWeightingMattersOnlyWithOutlierWeight) {
    // With w = 0 every omega_i = 1, so probreg's w vs w^2 Kabsch weighting is the same fit;
    // with w > 0 the weights vary and the two modes part.
    const PointCloud Y = testing::EllipsoidSurface(400, 6);
    const PointCloud X = Apply(SpecMotion(), Y);
    const AlignResult a =
        RunFilterReg(R"({"update_sigma2": false, "compat": "probreg", "maxiter": 5})", Y, X);
    const AlignResult b =
        RunFilterReg(R"({"update_sigma2": false, "compat": "none", "maxiter": 5})", Y, X);
    EXPECT_LT((a.T_target_source - b.T_target_source).cwiseAbs().maxCoeff(), 1e-9);
    const AlignResult c = RunFilterReg(
        R"({"update_sigma2": false, "compat": "probreg", "maxiter": 5, "w": 0.5})", Y, X);
    const AlignResult d =
        RunFilterReg(R"({"update_sigma2": false, "compat": "none", "maxiter": 5, "w": 0.5})", Y, X);
    EXPECT_GT((c.T_target_source - d.T_target_source).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(FilterReg, DeterministicAndThreadCountIndependent) {
    const Transform T = SpecMotion();
    const PointCloud Y = testing::BumpyEllipsoid(5000, 12);
    const PointCloud X = Apply(T, testing::BumpyEllipsoid(5000, 13));
    for (const char* params : {R"({"update_sigma2": true, "maxiter": 8})",
                               R"({"estimator": "exact", "sigma2": 0.003, "maxiter": 3})"}) {
        const int saved = omp_get_max_threads();
        omp_set_num_threads(1);
        const AlignResult one = RunFilterReg(params, Y, X);
        const AlignResult again = RunFilterReg(params, Y, X);
        omp_set_num_threads(2);
        const AlignResult two = RunFilterReg(params, Y, X);
        omp_set_num_threads(saved);
        ASSERT_EQ(one.status, AlignStatus::kOk) << one.message;
        EXPECT_EQ(one.T_target_source, again.T_target_source) << params;
        EXPECT_LT((one.T_target_source - two.T_target_source).cwiseAbs().maxCoeff(), 1e-9)
            << params;
    }
}

// ---- Parameters -----------------------------------------------------------------------------

TEST(FilterRegOptions, RejectsBadParametersNamingThem) {
    const std::pair<const char*, const char*> cases[] = {
        {R"({"w": 1.0})", "'w'"},
        {R"({"w": -0.1})", "'w'"},
        {R"({"maxiter": 0})", "'maxiter'"},
        {R"({"tol": -1})", "'tol'"},
        {R"({"min_sigma2": 0})", "'min_sigma2'"},
        {R"({"sigma2": -0.5})", "'sigma2'"},
        {R"({"objective": "pt2plane"})", "'objective'"},
        {R"({"estimator": "ifgt"})", "'estimator'"},
        {R"({"compat": "matlab"})", "'compat'"},
        {R"({"normals_k": 2})", "'normals_k'"},
        {R"({"update_sigma2": "yes"})", "'update_sigma2'"},
        {R"({"sigma_2": 0.1})", "'sigma_2'"},
    };
    for (const auto& [json, name] : cases) {
        try {
            ParseFilterRegOptions(nlohmann::json::parse(json));
            ADD_FAILURE() << json << " was accepted";
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("filterreg"), std::string::npos) << e.what();
        }
    }
}

TEST(FilterRegOptions, DefaultsAndCompatProbregSwitchesUpdateSigma2Off) {
    const FilterRegOptions defaults = ParseFilterRegOptions(nlohmann::json::object());
    EXPECT_TRUE(defaults.update_sigma2);
    EXPECT_EQ(defaults.compat, Compat::kNone);
    const FilterRegOptions probreg = ParseFilterRegOptions({{"compat", "probreg"}});
    EXPECT_FALSE(probreg.update_sigma2);
    EXPECT_EQ(probreg.maxiter, 50);
    EXPECT_EQ(probreg.tol, 1e-3);
    EXPECT_EQ(probreg.min_sigma2, 1e-4);
    EXPECT_TRUE(ParseFilterRegOptions({{"compat", "none"}}).update_sigma2);
    EXPECT_FALSE(
        ParseFilterRegOptions({{"compat", "none"}, {"update_sigma2", false}}).update_sigma2);
    EXPECT_EQ(ParseFilterRegOptions(nlohmann::json::parse(R"({"sigma2": null})")).sigma2, 0.0);
    auto method = CreateMethod("filterreg", {{"compat", "none"}});
    EXPECT_EQ(method->Params()["update_sigma2"], true);
}

TEST(FilterRegOptions, EveryParameterIsDocumented) {
    const MethodInfo& info = FindMethod("filterreg");
    for (const auto& item : info.defaults.items()) {
        EXPECT_TRUE(info.param_docs.count(item.key())) << item.key();
    }
    EXPECT_EQ(info.param_docs.size(), info.defaults.size());
}

}  // namespace
}  // namespace regbench
