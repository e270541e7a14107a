// The scale approximations of the GMM methods (cell compression, kd-tree cutoff, SVM
// subsample) on a 4k-point pair, forced on with low thresholds (defaults switch on at ~10k
// points), against the same method in its exact mode on the same pair. Budget: 0.5 degrees.
// At 4k points on this compact blob the default 0.1-sigma cells would not halve the cloud and
// the cutoff radius covers it, so the approximation would (rightly) stay off: the tests use
// 0.25-sigma cells, which do merge.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "core/rng.hpp"
#include "core/synthetic_shapes.hpp"
#include "core/transform.hpp"
#include "runners/registry.hpp"

namespace regbench {
namespace {

constexpr double kBudgetDeg = 0.5;

struct Pair4k {
    PointCloud source, target;
    Eigen::Matrix3d R;
};

Pair4k MakePair4k() {
    auto rng = MakePairRng(41, 0);
    Pair4k p;
    p.source = SmoothBlobSurface(rng, 4000);
    p.R = RotationFromAxisAngle({0.3, 0.1, 1.0}, 0.35);
    p.target = Apply(MakeTransform(p.R, {0.05, -0.03, 0.02}), SmoothBlobSurface(rng, 4000));
    return p;
}

double RotationDiffDeg(const AlignResult& a, const AlignResult& b) {
    return RotationAngleDeg(a.T_target_source.topLeftCorner<3, 3>(),
                            b.T_target_source.topLeftCorner<3, 3>());
}

/// A method's result on the 4k pair in its exact mode and with its approximations forced on.
struct BothModes {
    AlignResult dense, approx;
};

/// `method` on the 4k pair in its exact mode (kernel_sums dense) and with `approx_params`;
/// both calls must succeed, and extra[`flag`] must say the approximation was off in the
/// first and on in the second.
void AlignBothModes(const std::string& method, const nlohmann::json& approx_params,
                    const char* flag, BothModes* r) {
    const Pair4k p = MakePair4k();
    r->dense = CreateMethod(method, {{"kernel_sums", "dense"}})->Align(p.source, p.target);
    r->approx = CreateMethod(method, approx_params)->Align(p.source, p.target);
    ASSERT_EQ(r->dense.status, AlignStatus::kOk) << r->dense.message;
    ASSERT_EQ(r->approx.status, AlignStatus::kOk) << r->approx.message;
    EXPECT_FALSE(r->dense.extra[flag].get<bool>());
    EXPECT_TRUE(r->approx.extra[flag].get<bool>());
}

TEST(ApproximatedSums, GmmRegMatchesItsDenseModeOnFourThousandPoints) {
    BothModes r;
    ASSERT_NO_FATAL_FAILURE(
        AlignBothModes("gmmreg", {{"approx_min_pairs", 0}, {"compress_cell_sigmas", 0.25}},
                       "approximated_sums", &r));
    EXPECT_LT(RotationDiffDeg(r.dense, r.approx), kBudgetDeg);
}

TEST(ApproximatedSums, SvrWithSubsampledSvmAndApproximatedSumsMatchesDenseMode) {
    BothModes r;
    ASSERT_NO_FATAL_FAILURE(AlignBothModes(
        "svr", {{"approx_min_pairs", 0}, {"svm_max_points", 2000}}, "svm_subsampled", &r));
    // SVR's mixtures are its support vectors (a few hundred here, spread over the surface):
    // compressing them would not halve them and the cutoff radius covers the blob, so the
    // L2 sums rightly stay exact (gmm_l2_test checks those rules; the GMMReg test above the
    // accuracy of compression).
    EXPECT_FALSE(r.approx.extra["approximated_sums"].get<bool>());
    EXPECT_LT(RotationDiffDeg(r.dense, r.approx), kBudgetDeg);
}

}  // namespace
}  // namespace regbench
