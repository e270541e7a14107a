#pragma once
// The contract every registered method keeps, as parameterised tests of the method names:
// tests/baselines/method_contract_test.cpp runs them on every registered method, and
// tests/learned_example/learned_example_test.cpp on the worked example of
// docs/adding-a-learned-method.md, registered from outside the tree. An includer instantiates
// MethodContract with the names (MethodContractName names the tests); one source file per test
// executable includes it (its TEST_Ps define the tests).
#include <gtest/gtest.h>
#include <omp.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "core/rng.hpp"
#include "core/threads.hpp"
#include "core/transform.hpp"
#include "runners/registry.hpp"
#include "tests/baselines/synthetic_shape.hpp"

namespace regbench::testing {

struct IdentityTolerance {
    double rot_deg;
    double trans;
};

/// How close to the identity a method must stay on identical clouds. Exact-correspondence
/// methods land on it to rounding (the arccos in RotationAngleDeg resolves ~1e-6 deg); PCL
/// runs in float32; NDT's optimum fits the target's voxel Gaussians, not the points, and
/// sits ~0.5 deg off the identity on the 717-point crop. OMNet regresses the pose with no
/// fixed point at the identity: the shipped omnet-small (step 1408 of its CPU campaign,
/// docs/learned-methods.md) is 38.4 deg and 0.100 off on these identical clouds (37.3 and 0.166
/// at step 512: validation improved, this case did not), so its bound only catches a regression
/// from that (tighten it when the model registers identical clouds). Methods not listed get kDefault.
inline IdentityTolerance IdentityToleranceFor(const std::string& method) {
    static const std::map<std::string, IdentityTolerance> kTolerances = {
        {"identity", {1e-12, 1e-12}}, {"icp", {1e-5, 1e-9}},  {"icp-pl", {1e-5, 1e-9}},
        {"fgr", {1e-3, 1e-5}},        {"gicp", {0.01, 1e-4}}, {"ndt", {1.0, 0.01}},
        {"omnet", {40.0, 0.2}},
    };
    constexpr IdentityTolerance kDefault{1.0, 0.01};
    const auto it = kTolerances.find(method);
    return it == kTolerances.end() ? kDefault : it->second;
}

/// The registered methods' names, in registry order.
inline std::vector<std::string> MethodNames() {
    std::vector<std::string> names;
    for (const auto& m : AllMethods()) names.push_back(m.name);
    return names;
}

class MethodContract : public ::testing::TestWithParam<std::string> {
protected:
    static void SetUpTestSuite() {
        auto rng = MakePairRng(/*benchmark_seed=*/7, /*pair_index=*/0);
        source_ = new PointCloud(PartialCloud(rng));
        const Transform T_gt =
            MakeTransform(RotationXyzProductDeg(20.0, 10.0, 15.0), {0.1, -0.05, 0.05});
        target_ = new PointCloud(Apply(T_gt, PartialCloud(rng)));
    }
    static void TearDownTestSuite() {
        delete source_;
        delete target_;
    }
    std::unique_ptr<RegistrationMethod> Create() const { return CreateMethod(GetParam()); }

    inline static const PointCloud* source_ = nullptr;
    inline static const PointCloud* target_ = nullptr;
};

TEST_P(MethodContract, PartialPairGivesRigidTransform) {
    ASSERT_EQ(source_->rows(), 717);
    const AlignResult r = Create()->Align(*source_, *target_);
    ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
    const Eigen::Matrix3d R = r.T_target_source.topLeftCorner<3, 3>();
    EXPECT_TRUE(r.T_target_source.allFinite());
    EXPECT_NEAR(R.determinant(), 1.0, 1e-9);
    EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_EQ(r.T_target_source.row(3), Eigen::RowVector4d(0, 0, 0, 1));
    EXPECT_GE(r.iterations, 0);
    EXPECT_FALSE(r.stop_reason.empty());
}

TEST_P(MethodContract, IdenticalCloudsGiveNearIdentity) {
    const AlignResult r = Create()->Align(*source_, *source_);
    ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
    const IdentityTolerance tol = IdentityToleranceFor(GetParam());
    const double rot_deg =
        RotationAngleDeg(r.T_target_source.topLeftCorner<3, 3>(), Eigen::Matrix3d::Identity());
    EXPECT_LE(rot_deg, tol.rot_deg);
    const double trans = r.T_target_source.topRightCorner<3, 1>().norm();
    EXPECT_LE(trans, tol.trans);
}

/// SetOmpThreads for the scope; restores the previous count and OMP_NUM_THREADS after.
class ScopedOmpThreads {
public:
    explicit ScopedOmpThreads(int threads) : previous_(omp_get_max_threads()) {
        const char* env = std::getenv("OMP_NUM_THREADS");
        had_env_ = env != nullptr;
        if (had_env_) previous_env_ = env;
        SetOmpThreads(threads);
    }
    ~ScopedOmpThreads() {
        omp_set_num_threads(previous_);
        if (had_env_) {
            setenv("OMP_NUM_THREADS", previous_env_.c_str(), 1);
        } else {
            unsetenv("OMP_NUM_THREADS");
        }
    }

private:
    int previous_;
    bool had_env_ = false;
    std::string previous_env_;
};

TEST_P(MethodContract, ThreadCountDoesNotChangeResult) {
    constexpr double kThreadTol = 1e-9;
    AlignResult one;
    AlignResult two;
    {
        ScopedOmpThreads threads(1);
        one = Create()->Align(*source_, *target_);
    }
    {
        ScopedOmpThreads threads(2);
        two = Create()->Align(*source_, *target_);
    }
    ASSERT_EQ(one.status, AlignStatus::kOk) << one.message;
    ASSERT_EQ(two.status, AlignStatus::kOk) << two.message;
    EXPECT_LT((one.T_target_source - two.T_target_source).cwiseAbs().maxCoeff(), kThreadTol);
}

inline void ExpectFailsNaming(RegistrationMethod& method, const PointCloud& source,
                              const PointCloud& target, const std::string& expected_in_message) {
    const AlignResult r = method.Align(source, target);
    EXPECT_EQ(r.status, AlignStatus::kFailed);
    EXPECT_NE(r.message.find(expected_in_message), std::string::npos) << r.message;
    EXPECT_NE(r.message.find(method.Name()), std::string::npos) << r.message;
    EXPECT_TRUE(r.T_target_source.allFinite());
}

TEST_P(MethodContract, EmptyCloudFails) {
    auto method = Create();
    const PointCloud empty(0, 3);
    ExpectFailsNaming(*method, empty, *target_, "source cloud is empty");
    ExpectFailsNaming(*method, *source_, empty, "target cloud is empty");
}

TEST_P(MethodContract, TwoPointsFail) {
    auto method = Create();
    const PointCloud two = source_->topRows(2);
    ExpectFailsNaming(*method, two, *target_, "source cloud has 2 points");
    ExpectFailsNaming(*method, *source_, two, "target cloud has 2 points");
}

TEST_P(MethodContract, NonFiniteCoordinatesFail) {
    auto method = Create();
    for (const double bad :
         {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
        PointCloud corrupted = *source_;
        corrupted(100, 1) = bad;
        ExpectFailsNaming(*method, corrupted, *target_, "source cloud has non-finite");
        ExpectFailsNaming(*method, *source_, corrupted, "target cloud has non-finite");
    }
}

TEST_P(MethodContract, CoordinatesBeyondFloatRangeFailAsARow) {
    // 1e300 is finite in double but Inf in float: PCL's GICP/NDT aborted the process on it.
    // Issue 27: so did 1e30, which fits in a float but whose square does not; every method
    // refuses anything beyond the one documented limit kMaxCoordinate = 1e15 as a row.
    auto method = Create();
    for (const double big : {1e300, 3e38, 1e30, 2e15}) {
        PointCloud huge = *source_;
        huge(7, 0) = big;
        ExpectFailsNaming(*method, huge, *target_,
                          "source cloud has coordinates beyond the limit |x| <= 1e15");
        ExpectFailsNaming(*method, *source_, huge,
                          "target cloud has coordinates beyond the limit |x| <= 1e15");
    }
}

TEST_P(MethodContract, UnknownParameterIsNamed) {
    const MethodInfo& info = FindMethod(GetParam());
    try {
        info.create({{"no_such_parameter", 1}});
        FAIL() << "expected std::invalid_argument";
    } catch (const std::invalid_argument& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("no_such_parameter"), std::string::npos) << what;
        EXPECT_NE(what.find(GetParam()), std::string::npos) << what;
    }
}

TEST_P(MethodContract, DefaultsRoundTripAndAreDocumented) {
    const MethodInfo& info = FindMethod(GetParam());
    EXPECT_FALSE(info.summary.empty());
    EXPECT_EQ(Create()->Params(), info.defaults);
    // Every parameter is settable through JSON: passing all defaults explicitly is accepted.
    EXPECT_EQ(info.create(info.defaults)->Params(), info.defaults);
    for (const auto& item : info.defaults.items()) {
        const auto doc = info.param_docs.find(item.key());
        ASSERT_NE(doc, info.param_docs.end()) << "undocumented parameter " << item.key();
        EXPECT_FALSE(doc->second.empty());
    }
    for (const auto& doc : info.param_docs) {
        EXPECT_TRUE(info.defaults.contains(doc.first)) << "doc for unknown key " << doc.first;
    }
}

/// The test name of method `info.param`: its name, non-alphanumerics as '_'.
inline std::string MethodContractName(const ::testing::TestParamInfo<std::string>& info) {
    std::string name = info.param;
    for (char& c : name) {
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    }
    return name;
}

}  // namespace regbench::testing
