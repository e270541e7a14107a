// gicp and ndt (PCL).
#include <gtest/gtest.h>

#include "runners/registry.hpp"
#include "tests/baselines/registration_fixtures.hpp"

namespace regbench {
namespace {

using testing::AlignOk;
using testing::CleanCompletePair;

// Recovery of a known motion (gicp 10 degrees, ndt 5): clean_pair_recovery_test.cpp.

TEST(Gicp, CloudSmallerThanNeighbourhoodFails) {
    const auto pair = CleanCompletePair(10.0);
    const PointCloud small = pair.source.topRows(10);
    const AlignResult r = CreateMethod("gicp")->Align(small, pair.target);
    EXPECT_EQ(r.status, AlignStatus::kFailed);
    EXPECT_NE(r.message.find("correspondence_randomness"), std::string::npos) << r.message;
}

TEST(Gicp, DistantCloudsStopWithOptimizerError) {
    // No pair within max_correspondence_distance: PCL's BFGS step throws and leaves the input
    // unchanged. Issue 26: this was status ok with 0 iterations; an internal error is now a
    // failed call with the reason (and the identity fallback).
    auto pair = CleanCompletePair(0.0);
    pair.target.col(0).array() += 10.0;
    const AlignResult r = CreateMethod("gicp")->Align(pair.source, pair.target);
    EXPECT_EQ(r.status, AlignStatus::kFailed);
    EXPECT_EQ(r.stop_reason, "optimizer_error");
    EXPECT_NE(r.message.find("optimizer_error"), std::string::npos) << r.message;
    EXPECT_TRUE(r.T_target_source.isIdentity(1e-12));
}

TEST(Ndt, NoProgressOnADistantPairFailsInsteadOfClaimingConvergence) {
    // The target 10 units away (the clouds span about 1): no source point lies near any target
    // cell, so PCL's first Newton step is exactly zero and it returned the identity as
    // "0 iterations | converged" with status ok (issue 26).
    auto pair = CleanCompletePair(0.0);
    pair.target.col(0).array() += 10.0;
    const AlignResult r = CreateMethod("ndt")->Align(pair.source, pair.target);
    EXPECT_EQ(r.status, AlignStatus::kFailed);
    EXPECT_EQ(r.iterations, 0);
    EXPECT_EQ(r.stop_reason, "no_progress");
    EXPECT_NE(r.message.find("0 iterations"), std::string::npos) << r.message;
    // An aligned input is not a failure: NDT still takes steps (or scores > 0).
    const AlignResult ok = CreateMethod("ndt")->Align(pair.source, pair.source);
    EXPECT_EQ(ok.status, AlignStatus::kOk) << ok.message;
}

TEST(Ndt, ResolutionWithoutPopulatedVoxelsFails) {
    const auto pair = CleanCompletePair(5.0);
    const AlignResult r =
        CreateMethod("ndt", {{"resolution", 0.001}})->Align(pair.source, pair.target);
    EXPECT_EQ(r.status, AlignStatus::kFailed);
    EXPECT_NE(r.message.find("no target voxel"), std::string::npos) << r.message;
}

}  // namespace
}  // namespace regbench
