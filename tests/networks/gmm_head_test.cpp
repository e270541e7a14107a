#include "networks/layers/gmm_head.hpp"

#include <gtest/gtest.h>

#include "core/transform.hpp"

namespace regbench::networks {
namespace {

TEST(GmmHead, ParamsOfHardAssignmentsAreClusterMeansAndVariances) {
    // Two clusters of two points each: mu = midpoints, s = total variance = |half gap|^2.
    auto xyz = torch::tensor({0.f, 0.f, 0.f, 2.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 3.f, 0.f})
                   .reshape({1, 4, 3});
    auto gamma = torch::tensor({1.f, 0.f, 1.f, 0.f, 0.f, 1.f, 0.f, 1.f}).reshape({1, 4, 2});
    const GmmParams g = ComputeGmmParams(gamma, xyz);
    EXPECT_NEAR(g.pi[0][0].item<float>(), 0.5f, 1e-6);
    EXPECT_NEAR(g.mu[0][0][0].item<float>(), 1.0f, 1e-6);
    EXPECT_NEAR(g.mu[0][1][1].item<float>(), 2.0f, 1e-6);
    EXPECT_NEAR(g.sigma[0][0].item<float>(), 1.0f, 1e-6);
    EXPECT_NEAR(g.sigma[0][1].item<float>(), 1.0f, 1e-6);
}

TEST(GmmHead, RegisterRecoversAKnownTransformFromMatchedMeans) {
    torch::manual_seed(3);
    const auto mu_s = torch::rand({1, 16, 3}, torch::kFloat64) - 0.5;
    const Eigen::Matrix3d R = RotationFromEulerZyxDeg(30, -20, 40);
    const Eigen::Vector3d t(0.1, -0.2, 0.3);
    auto Rt = torch::empty({3, 3}, torch::kFloat64);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) Rt[r][c] = R(r, c);
    }
    const auto tt = torch::tensor({t.x(), t.y(), t.z()}, torch::kFloat64);
    const auto mu_t = torch::matmul(mu_s, Rt.transpose(0, 1)) + tt;
    const auto pi = torch::full({1, 16}, 1.0 / 16, torch::kFloat64);
    const auto sigma = torch::full({1, 16}, 0.01, torch::kFloat64);
    const auto T = GmmRegister(pi, mu_s, mu_t, sigma);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(T[0][r][c].item<double>(), R(r, c), 1e-9);
        EXPECT_NEAR(T[0][r][3].item<double>(), t[r], 1e-9);
    }
    EXPECT_NEAR(torch::det(T[0]).item<double>(), 1.0, 1e-9);
}

TEST(GmmHead, SinkhornMatchesItsMarginals) {
    torch::manual_seed(4);
    const auto cost = torch::rand({2, 6, 4}, torch::kFloat64);
    const auto p = torch::full({2, 6}, 1.0 / 6, torch::kFloat64);
    const auto q = torch::full({2, 4}, 1.0 / 4, torch::kFloat64);
    const auto G = LogSinkhorn(cost, p, q, 0.1, 1e-12, 500);
    EXPECT_LT((G.sum(2) - p).abs().max().item<double>(), 1e-6);
    EXPECT_LT((G.sum(1) - q).abs().max().item<double>(), 1e-6);
}

}  // namespace
}  // namespace regbench::networks
