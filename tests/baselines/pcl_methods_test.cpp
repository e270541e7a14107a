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
    // No pair within max_correspondence_distance: PCL's BFGS step throws, the method returns
    // the identity and says why instead of claiming convergence.
    auto pair = CleanCompletePair(0.0);
    pair.target.col(0).array() += 10.0;
    const AlignResult r = AlignOk("gicp", pair);
    EXPECT_EQ(r.stop_reason, "optimizer_error");
    EXPECT_TRUE(r.T_target_source.isIdentity(1e-12));
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
