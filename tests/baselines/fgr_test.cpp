#include <gtest/gtest.h>

#include "runners/registry.hpp"
#include "tests/baselines/registration_fixtures.hpp"

namespace regbench {
namespace {

using testing::CleanCompletePair;
using testing::RreDeg;

TEST(Fgr, RecoversLargeMotionOnCleanCompletePair) {
    // Global: no initial guess needed, identical points give identical FPFH descriptors.
    constexpr double kRreTolDeg = 1.0;
    const auto pair = CleanCompletePair(60.0);
    const AlignResult r = CreateMethod("fgr")->Align(pair.source, pair.target);
    ASSERT_EQ(r.status, AlignStatus::kOk) << r.message;
    EXPECT_LT(RreDeg(pair, r.T_target_source), kRreTolDeg);
    EXPECT_EQ(r.iterations, 64);
}

TEST(Fgr, SameSeedGivesSameResult) {
    const auto pair = CleanCompletePair(30.0, /*seed=*/5);
    auto method = CreateMethod("fgr");
    const AlignResult a = method->Align(pair.source, pair.target);
    // A call with another seed in between must not leak into the next call.
    CreateMethod("fgr", {{"seed", 99}})->Align(pair.source, pair.target);
    const AlignResult b = method->Align(pair.source, pair.target);
    ASSERT_EQ(a.status, AlignStatus::kOk) << a.message;
    EXPECT_EQ(a.T_target_source, b.T_target_source);
}

TEST(Fgr, TupleScaleIsValidated) {
    EXPECT_THROW(CreateMethod("fgr", {{"tuple_scale", 1.5}}), std::invalid_argument);
}

}  // namespace
}  // namespace regbench
