#pragma once
// Test-only pairs with known motion for the per-method tests.
#include <gtest/gtest.h>

#include <string>

#include "core/math_constants.hpp"
#include "core/rng.hpp"
#include "core/transform.hpp"
#include "runners/registry.hpp"
#include "tests/baselines/synthetic_shape.hpp"

namespace regbench::testing {

struct KnownPair {
    PointCloud source;
    PointCloud target;
    Transform T_gt;
};

/// Clean complete pair: 1024 samples, target = T_gt(source) point for point, with a
/// rotation of `angle_deg` about a fixed oblique axis and a small translation.
inline KnownPair CleanCompletePair(double angle_deg, std::uint64_t seed = 11) {
    auto rng = MakePairRng(seed, 0);
    KnownPair pair;
    pair.source = SampleBumpyEllipsoid(rng, 1024);
    const Eigen::Matrix3d R = RotationFromAxisAngle({1.0, 0.5, -0.3}, angle_deg * kPi / 180.0);
    pair.T_gt = MakeTransform(R, {0.03, -0.02, 0.01});
    pair.target = Apply(pair.T_gt, pair.source);
    return pair;
}

/// Rotation error in degrees of an estimate against the pair's ground truth.
inline double RreDeg(const KnownPair& pair, const Transform& T_est) {
    return RotationAngleDeg(pair.T_gt.topLeftCorner<3, 3>(), T_est.topLeftCorner<3, 3>());
}

/// Aligns `source` to `target` with a fresh `method` built from `params`.
inline AlignResult AlignWith(const std::string& method, const nlohmann::json& params,
                             const PointCloud& source, const PointCloud& target) {
    return CreateMethod(method, params)->Align(source, target);
}

/// Aligns the pair with a fresh `method` built from `params`, and fails the test (naming the
/// method's message) unless the call returned a transform.
inline AlignResult AlignOk(const std::string& method, const KnownPair& pair,
                           const nlohmann::json& params = nlohmann::json::object()) {
    const AlignResult r = AlignWith(method, params, pair.source, pair.target);
    EXPECT_EQ(r.status, AlignStatus::kOk) << method << ": " << r.message;
    return r;
}

}  // namespace regbench::testing
