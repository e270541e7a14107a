#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "runners/registry.hpp"
#include "tests/baselines/registration_fixtures.hpp"

namespace regbench {
namespace {

using testing::CleanCompletePair;

// Recovery of a 60-degree motion: clean_pair_recovery_test.cpp.

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

TEST(Fgr, ConcurrentCallsMatchSequentialOnes) {
    // Open3D's random engine is process-wide: concurrent calls (runner --jobs) must not
    // interleave their seeded draws.
    constexpr int kThreads = 4;
    std::vector<testing::KnownPair> pairs;
    std::vector<Transform> sequential;
    for (int i = 0; i < kThreads; ++i) {
        pairs.push_back(CleanCompletePair(20.0 + 10.0 * i, /*seed=*/20 + i));
        sequential.push_back(
            CreateMethod("fgr")->Align(pairs[i].source, pairs[i].target).T_target_source);
    }
    for (int repeat = 0; repeat < 3; ++repeat) {
        std::vector<Transform> concurrent(kThreads);
        std::vector<std::thread> threads;
        for (int i = 0; i < kThreads; ++i) {
            threads.emplace_back([&, i] {
                concurrent[i] =
                    CreateMethod("fgr")->Align(pairs[i].source, pairs[i].target).T_target_source;
            });
        }
        for (auto& t : threads) t.join();
        for (int i = 0; i < kThreads; ++i) EXPECT_EQ(concurrent[i], sequential[i]) << i;
    }
}

TEST(Fgr, TupleScaleIsValidated) {
    EXPECT_THROW(CreateMethod("fgr", {{"tuple_scale", 1.5}}), std::invalid_argument);
}

}  // namespace
}  // namespace regbench
