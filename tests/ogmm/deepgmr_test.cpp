#include "ogmm/deepgmr.hpp"

#include <gtest/gtest.h>

#include "core/rng.hpp"
#include "core/synthetic_shapes.hpp"
#include "core/transform.hpp"
#include "ogmm/gmm_head.hpp"
#include "ogmm/zoo.hpp"

namespace regbench::ogmm {
namespace {

torch::Tensor Cloud(int64_t b, int64_t n, std::uint64_t seed) {
    torch::Tensor t = torch::empty({b, n, 3}, torch::kFloat);
    for (int64_t s = 0; s < b; ++s) {
        std::mt19937_64 rng = MakePairRng(seed, s);
        const PointCloud p = BumpyEllipsoidSurface(rng, n);
        for (int64_t i = 0; i < n; ++i) {
            for (int c = 0; c < 3; ++c) t[s][i][c] = static_cast<float>(p(i, c));
        }
    }
    return t;
}

class DeepGmrShapes : public ::testing::TestWithParam<std::string> {};

TEST_P(DeepGmrShapes, ForwardShapesAndNormalisationAtPaperSizes) {
    torch::set_num_threads(1);
    torch::manual_seed(0);
    auto net = MakeNet(GetParam());
    net->eval();
    torch::NoGradGuard no_grad;
    const int J = net->Config().at("clusters").get<int>();
    for (int64_t b : {1, 4}) {
        for (int64_t n : {717, 1024, 1433}) {
            SCOPED_TRACE("B=" + std::to_string(b) + " N=" + std::to_string(n));
            PairBatch batch;
            batch.source = Cloud(b, n, 1);
            batch.target = Cloud(b, n, 2);
            const NetOutput out = net->Forward(batch);
            ASSERT_EQ(out.T.sizes(), (std::vector<int64_t>{b, 4, 4}));
            const torch::Tensor gamma = out.aux.at("gamma_source");
            ASSERT_EQ(gamma.sizes(), (std::vector<int64_t>{b, n, J}));
            EXPECT_LT((gamma.sum(2) - 1).abs().max().item<float>(), 1e-4);
            EXPECT_LT((out.aux.at("pi_target").sum(1) - 1).abs().max().item<float>(), 1e-4);
            // A rotation block with det +1 (the closed form's reflection guard).
            const torch::Tensor R =
                out.T.index({torch::indexing::Slice(), torch::indexing::Slice(0, 3),
                             torch::indexing::Slice(0, 3)});
            EXPECT_LT((torch::det(R) - 1).abs().max().item<float>(), 1e-4);
        }
    }
}

INSTANTIATE_TEST_SUITE_P(
    AllConfigs,
    DeepGmrShapes,
    ::testing::Values("deepgmr", "deepgmr-small", "deepgmr-orig", "deepgmr-orig-xyz"),
    [](const auto& info) {
        std::string s = info.param;
        for (char& c : s) c = c == '-' ? '_' : c;
        return s;
    });

TEST(DeepGmr, ClosedFormRecoversAKnownMotionWithUnequalWeightsAndVariances) {
    // Hand-made mixtures: 8 source means, target means = R mu + t exactly, uneven pi and
    // target variances. Any positive weighting of exact correspondences gives the motion back.
    torch::manual_seed(7);
    const auto mu_s = torch::randn({1, 8, 3}, torch::kFloat64);
    const Eigen::Matrix3d R = RotationFromAxisAngle(Eigen::Vector3d(1, 2, -1).normalized(), 2.5);
    const Eigen::Vector3d t(-0.4, 0.25, 0.9);
    torch::Tensor Rt = torch::empty({3, 3}, torch::kFloat64);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) Rt[r][c] = R(r, c);
    }
    const auto mu_t =
        torch::matmul(mu_s, Rt.t()) + torch::tensor({t.x(), t.y(), t.z()}, torch::kFloat64);
    auto pi = torch::rand({1, 8}, torch::kFloat64) + 0.1;
    pi = pi / pi.sum();
    const auto sigma_t = torch::rand({1, 8}, torch::kFloat64) + 0.05;
    const auto T = GmmRegister(pi, mu_s, mu_t, sigma_t);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(T[0][r][c].item<double>(), R(r, c), 1e-9);
        EXPECT_NEAR(T[0][r][3].item<double>(), t[r], 1e-9);
    }
}

TEST(DeepGmr, PoseLossIsZeroAtTheTruthAndMatchesItsFormula) {
    torch::manual_seed(1);
    auto net = MakeNet("deepgmr-orig-xyz");  // loss overridden below via the config switch
    DeepGmrConfig c = DeepGmrConfigFromJson(net->Config());
    c.loss = DeepGmrLoss::kPose;
    DeepGmrNet pose_net(c);
    PairBatch batch;
    const Transform T = MakeTransform(RotationFromEulerZyxDeg(10, 20, 30), {0.1, 0.2, 0.3});
    torch::Tensor Tt = torch::empty({1, 4, 4}, torch::kFloat);
    for (int r = 0; r < 4; ++r) {
        for (int k = 0; k < 4; ++k) Tt[0][r][k] = static_cast<float>(T(r, k));
    }
    batch.T_gt = Tt;
    NetOutput out;
    out.T = Tt.clone();
    EXPECT_NEAR(pose_net.Loss(batch, out).at("total").item<float>(), 0.0f, 1e-10);
    // Translation off by (0.3, 0, 0): mean over 3 entries of 0.09 = 0.03; rotation term 0.
    out.T[0][0][3] += 0.3f;
    const LossTerms terms = pose_net.Loss(batch, out);
    EXPECT_NEAR(terms.at("translation").item<float>(), 0.03f, 1e-6);
    EXPECT_NEAR(terms.at("rotation").item<float>(), 0.0f, 1e-10);
}

TEST(DeepGmr, ConfigRoundTripsAndRejectsUnknownKeys) {
    const nlohmann::json j = NamedConfig("deepgmr-small");
    nlohmann::json net_only = j;
    net_only.erase("train");
    EXPECT_EQ(ToJson(DeepGmrConfigFromJson(net_only)), net_only);
    EXPECT_THROW(MakeNet("deepgmr-small", {{"colour", 1}}), std::invalid_argument);
    EXPECT_THROW(MakeNet("deepgmr-small", {{"features", "ppf"}}), std::invalid_argument);
    EXPECT_THROW(NamedConfig("deepgmr-huge"), std::invalid_argument);
}

TEST(DeepGmr, OriginalParameterCountMatchesTheReference) {
    // deepgmr.md section 7 (counted from the original PyTorch module): 1,527,440 with RRI input,
    // 1,522,512 with xyz input.
    EXPECT_EQ(CountParameters(*MakeNet("deepgmr-orig")), 1527440);
    EXPECT_EQ(CountParameters(*MakeNet("deepgmr-orig-xyz")), 1522512);
}

}  // namespace
}  // namespace regbench::ogmm
