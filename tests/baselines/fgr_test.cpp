#include <gtest/gtest.h>

#include <random>
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

/// `n` points uniform in the cube [-1, 1]^3 from `seed`: no shape, so no feature agrees.
PointCloud UniformCube(int n, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    PointCloud p(n, 3);
    for (int i = 0; i < n; ++i) {
        for (int c = 0; c < 3; ++c) p(i, c) = u(rng);
    }
    return p;
}

TEST(Fgr, NoCorrespondencesIsAFailedCall) {
    // Issue 54 item 5: FGR on clouds with nothing in common (independent uniform points, no
    // shape) returned a transform with 0 inlier correspondences as `ok` (a run printed
    // {"correspondences": 0, "fitness": 0.0} with status ok for each of these three seeds, and
    // for the pairs of the overlap and density sweeps). Such a call fails, saying why, and
    // carries the identity like every failed call.
    for (std::uint64_t seed : {1, 2, 3}) {
        SCOPED_TRACE(seed);
        const AlignResult r =
            CreateMethod("fgr")->Align(UniformCube(300, seed), UniformCube(300, seed + 10));
        EXPECT_EQ(r.extra.at("correspondences").get<std::size_t>(), 0u);
        EXPECT_EQ(r.status, AlignStatus::kFailed);
        EXPECT_EQ(r.stop_reason, "no_correspondences");
        EXPECT_EQ(r.T_target_source, Transform::Identity());
        EXPECT_NE(r.message.find("no evidence for a transform: 0 correspondences within the max "
                                 "correspondence distance 0.025"),
                  std::string::npos)
            << r.message;
    }
    // The same method on a clean pair finds its correspondences and stays ok.
    const auto pair = CleanCompletePair(30.0, /*seed=*/5);
    const AlignResult ok = CreateMethod("fgr")->Align(pair.source, pair.target);
    EXPECT_EQ(ok.status, AlignStatus::kOk) << ok.message;
    EXPECT_GE(ok.extra.at("correspondences").get<std::size_t>(), 3u);
}

TEST(Fgr, OpenThreeDsFallbackWithoutFeatureMatchesIsAFailedCall) {
    // With fewer than 10 FPFH matches after its tuple test, Open3D's FGR skips the optimisation
    // and returns the identity in its normalised frame: the unrotated centroid shift, its
    // rotation block exactly I (6 of 10 overlap-sweep and 6 of 10 density pairs of the cgal
    // test split, seed 1, were such `ok` rows, with 6 to 40 of 717 points within the max
    // correspondence distance after it). Here 15 shared points and 15 others on each side,
    // the others' centroids equal (so the shift is 0): sparse points, no features, the
    // fallback (a probe printed its exact identity rotation), half the source points land.
    const PointCloud shared = UniformCube(15, 1), own_source = UniformCube(15, 101);
    PointCloud own_target = UniformCube(15, 201);
    own_target.rowwise() += own_source.colwise().mean() - own_target.colwise().mean();
    PointCloud source(30, 3), target(30, 3);
    source << shared, own_source;
    target << shared, own_target;
    const AlignResult r = CreateMethod("fgr")->Align(source, target);
    EXPECT_EQ(r.status, AlignStatus::kFailed);
    EXPECT_EQ(r.stop_reason, "no_feature_matches");
    EXPECT_NE(r.message.find("no evidence for a transform: fewer than 10 FPFH matches passed "
                             "FGR's tuple test"),
              std::string::npos)
        << r.message;
    EXPECT_NE(r.message.find("(15 of 30 source points within 0.025 after it)"), std::string::npos)
        << r.message;
    // The same fallback on a translated copy (seed 2: a probe printed the exact identity
    // rotation too) aligns every point: the one case where the shift is evidence, kept ok.
    const PointCloud copy = UniformCube(20, 2);
    PointCloud moved = copy;
    moved.col(0).array() += 0.3;
    const AlignResult kept = CreateMethod("fgr")->Align(copy, moved);
    EXPECT_TRUE((kept.T_target_source.topLeftCorner<3, 3>() == Eigen::Matrix3d::Identity()));
    EXPECT_EQ(kept.status, AlignStatus::kOk) << kept.message;
    EXPECT_EQ(kept.extra.at("correspondences").get<std::size_t>(), 20u);
}

TEST(Fgr, TupleScaleIsValidated) {
    EXPECT_THROW(CreateMethod("fgr", {{"tuple_scale", 1.5}}), std::invalid_argument);
}

}  // namespace
}  // namespace regbench
