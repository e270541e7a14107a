#include <gtest/gtest.h>

#include "runners/registry.hpp"
#include "tests/baselines/registration_fixtures.hpp"

namespace regbench {
namespace {

using testing::AlignOk;
using testing::CleanCompletePair;
using testing::RreDeg;

constexpr double kRreTolDeg = 0.5;

// Recovery of a 10-degree motion (icp, icp-pl): clean_pair_recovery_test.cpp.

TEST(Icp, MaxIterationsIsApplied) {
    const auto pair = CleanCompletePair(10.0);
    const AlignResult r = AlignOk("icp", pair, {{"max_iterations", 1}});
    EXPECT_EQ(r.iterations, 1);
    EXPECT_EQ(r.stop_reason, "max_iterations");
    EXPECT_GT(RreDeg(pair, r.T_target_source), kRreTolDeg);  // one step is not enough
}

TEST(Icp, DistantCloudsHaveNoCorrespondences) {
    auto pair = CleanCompletePair(0.0);
    pair.target.col(0).array() += 10.0;
    const AlignResult r = AlignOk("icp", pair);
    EXPECT_EQ(r.stop_reason, "no_correspondences");
    EXPECT_TRUE(r.T_target_source.isIdentity());
    EXPECT_EQ(r.extra.at("correspondences"), 0);
}

TEST(Icp, OutOfRangeParameterIsNamed) {
    try {
        CreateMethod("icp", {{"max_correspondence_distance", -1.0}});
        FAIL() << "expected std::invalid_argument";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("'max_correspondence_distance'"), std::string::npos)
            << e.what();
    }
}

TEST(IcpPl, NormalNeighbourCountIsValidated) {
    EXPECT_THROW(CreateMethod("icp-pl", {{"normal_max_nn", 2}}), std::invalid_argument);
}

}  // namespace
}  // namespace regbench
