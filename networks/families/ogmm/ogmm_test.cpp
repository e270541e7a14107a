#include "networks/families/ogmm/net.hpp"

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "core/transform.hpp"
#include "tests/networks/formula_fixture.hpp"
#include "tests/networks/one_thread_test.hpp"

namespace regbench::networks {
namespace {

using torch::indexing::Slice;

class OgmmNetTest : public OneThreadTest {};

torch::Tensor RotationTensor(const Eigen::Matrix3d& R, torch::Dtype dtype) {
    torch::Tensor t = torch::empty({3, 3}, torch::kFloat64);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) t[r][c] = R(r, c);
    }
    return t.to(dtype);
}

// ---- configuration -------------------------------------------------------------------------

TEST_F(OgmmNetTest, NamedConfigsBuildAndRoundTrip) {
    for (const std::string name : {"ogmm", "ogmm-small", "ogmm-tiny"}) {
        const nlohmann::json config = OgmmNamedConfig(name);
        const auto net = MakeOgmmNet(config);
        EXPECT_EQ(net->Config(), config) << name;
        EXPECT_EQ(ParseOgmmConfig(net->Config()).emb_dims, config["emb_dims"]);
    }
    EXPECT_EQ(OgmmNamedConfig("ogmm-small")["clusters"], 32);
    EXPECT_EQ(OgmmNamedConfig("ogmm-tiny")["anchors"], 16);
    EXPECT_THROW(OgmmNamedConfig("ogmm-huge"), std::invalid_argument);
}

// Expects MakeOgmmNet(patch over the tiny config) to throw a message naming `key`.
void ExpectRejected(const nlohmann::json& patch, const std::string& key) {
    nlohmann::json config = OgmmNamedConfig("ogmm-tiny");
    config.merge_patch(patch);
    try {
        MakeOgmmNet(config);
        ADD_FAILURE() << "accepted " << patch.dump();
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("'" + key + "'"), std::string::npos) << e.what();
    }
}

TEST_F(OgmmNetTest, BadConfigsAreRejectedNamingTheKey) {
    ExpectRejected({{"emb_dim", 64}}, "emb_dim");  // unknown key
    ExpectRejected({{"emb_dims", 63}}, "emb_dims");
    ExpectRejected({{"emb_dims", 66}}, "emb_dims");  // not divisible by 4 heads
    ExpectRejected({{"anchors", 0}}, "anchors");
    ExpectRejected({{"anchors", 1.5}}, "anchors");
    ExpectRejected({{"clusters", 2}}, "clusters");
    ExpectRejected({{"attention", "sparse"}}, "attention");
    ExpectRejected({{"spe", "yes"}}, "spe");
    ExpectRejected({{"w_welsch", -1.0}}, "w_welsch");
    ExpectRejected({{"sinkhorn_epsilon", 0.0}}, "sinkhorn_epsilon");
}

TEST_F(OgmmNetTest, ParameterCountsMatchTheAuthorsModelAndTheAblations) {
    // The authors' model has 13,022,210 parameters (sum of the per-block counts checked in
    // layers_test: DGCNN 309,632, SPE 297,344 incl. its unused conv, 3 attentions of 2,625,024,
    // CONV3_a 2,103,808, CONV3_b 2,105,856, proj 132,097, overlap CONV3 198,401).
    const nlohmann::json full = OgmmNamedConfig("ogmm");
    EXPECT_EQ(CountParameters(*MakeOgmmNet(full)), 13022210);
    nlohmann::json no_csa = full;
    no_csa["csa"] = false;  // drops the two self-attention blocks
    EXPECT_EQ(CountParameters(*MakeOgmmNet(no_csa)), 13022210 - 2 * 2625024);
    nlohmann::json no_spe = full;
    no_spe["spe"] = false;
    EXPECT_EQ(CountParameters(*MakeOgmmNet(no_spe)), 13022210 - 297344);
    nlohmann::json no_osp = full;
    no_osp["osp"] = false;  // drops proj, CONV3_b and the overlap CONV3
    EXPECT_EQ(CountParameters(*MakeOgmmNet(no_osp)), 13022210 - 132097 - 2105856 - 198401);
    nlohmann::json dense = full;
    dense["attention"] = "full";  // same weights, different anchors
    EXPECT_EQ(CountParameters(*MakeOgmmNet(dense)), 13022210);
}

// ---- forward shapes for every named config ---------------------------------------------------

class OgmmShapes : public ::testing::TestWithParam<std::tuple<std::string, int64_t, int64_t>> {
protected:
    void SetUp() override { torch::set_num_threads(1); }
    // One network per named config for the whole suite (the full one has 13 M parameters).
    static std::shared_ptr<RegistrationNet> Net(const std::string& name) {
        static std::map<std::string, std::shared_ptr<RegistrationNet>> nets;
        if (!nets.count(name)) {
            nets[name] = MakeOgmmNet(OgmmNamedConfig(name));
            nets[name]->eval();
        }
        return nets[name];
    }
};

TEST_P(OgmmShapes, ForwardGivesRigidTransformsAndPerPointScores) {
    const auto& [name, points, batch] = GetParam();
    const auto net = Net(name);
    const nlohmann::json config = net->Config();
    const int64_t d = config["emb_dims"], J = config["clusters"];
    torch::manual_seed(11);
    PairBatch pairs;
    pairs.source = torch::rand({batch, points, 3}) - 0.5;
    pairs.target = torch::rand({batch, points, 3}) - 0.5;
    torch::NoGradGuard no_grad;  // inference: keeps the full config at 1433 points affordable
    const NetOutput out = net->Forward(pairs);
    ASSERT_EQ(out.T.sizes(), (std::vector<int64_t>{batch, 4, 4}));
    const torch::Tensor R = out.T.index({Slice(), Slice(0, 3), Slice(0, 3)});
    const torch::Tensor I = torch::eye(3).expand({batch, 3, 3});
    EXPECT_LT((torch::bmm(R.transpose(1, 2), R) - I).abs().max().item<float>(), 1e-4);
    EXPECT_LT((torch::det(R) - 1).abs().max().item<float>(), 1e-4);
    const std::vector<int64_t> per_point{batch, points};
    EXPECT_EQ(out.aux.at("overlap_source").sizes(), per_point);
    EXPECT_EQ(out.aux.at("overlap_target").sizes(), per_point);
    EXPECT_EQ(out.aux.at("gamma_source").sizes(), (std::vector<int64_t>{batch, points, J}));
    EXPECT_EQ(out.aux.at("mu_target").sizes(), (std::vector<int64_t>{batch, J, 3}));
    EXPECT_EQ(out.aux.at("nu_source").sizes(), (std::vector<int64_t>{batch, J, d}));
    EXPECT_EQ(out.aux.at("features_target").sizes(), (std::vector<int64_t>{batch, d, points}));
    const torch::Tensor op = out.aux.at("overlap_source");
    EXPECT_TRUE(((op > 0) & (op < 1)).all().item<bool>());
    EXPECT_TRUE(torch::isfinite(out.T).all().item<bool>());
}

INSTANTIATE_TEST_SUITE_P(NamedConfigs, OgmmShapes,
                         ::testing::Combine(::testing::Values("ogmm", "ogmm-small", "ogmm-tiny"),
                                            ::testing::Values(717, 1024, 1433),
                                            ::testing::Values(1, 4)),
                         [](const auto& info) {
                             std::string name = std::get<0>(info.param);
                             for (auto& c : name) c = c == '-' ? '_' : c;
                             return name + "_" + std::to_string(std::get<1>(info.param)) + "pts_b" +
                                    std::to_string(std::get<2>(info.param));
                         });

// ---- GMM fit and closed form ------------------------------------------------------------------

TEST_F(OgmmNetTest, GammaRowsAndMixtureWeightsSumToOne) {
    // Through the whole network (tiny config, 717 points): overlap masses w_i ~ 1/717 stay above
    // the code's 1e-3 row clip, so every responsibility row is normalised.
    auto net = MakeOgmmNet(OgmmNamedConfig("ogmm-tiny"));
    net->eval();
    torch::manual_seed(5);
    PairBatch pairs;
    pairs.source = torch::rand({2, 717, 3}) - 0.5;
    pairs.target = torch::rand({2, 717, 3}) - 0.5;
    torch::NoGradGuard no_grad;
    const NetOutput out = net->Forward(pairs);
    for (const char* side : {"source", "target"}) {
        const torch::Tensor gamma = out.aux.at(std::string("gamma_") + side);
        const torch::Tensor pi = out.aux.at(std::string("pi_") + side);
        EXPECT_LT((gamma.sum(2) - 1).abs().max().item<float>(), 1e-5) << side;
        EXPECT_LT((pi.sum(1) - 1).abs().max().item<float>(), 1e-5) << side;
        EXPECT_GE(gamma.min().item<float>(), 0.0f);
    }
}

TEST_F(OgmmNetTest, SoftMatchingAndKabschRecoverAKnownMotionFromSyntheticClusters) {
    // Eight Gaussian blobs, the target is the exactly moved source (same point order), uniform
    // overlap. FPS from the centroid and the Sinkhorn fit only see distances, so the target's
    // means are the moved source means; one-hot cluster features make the soft matching the
    // identity permutation, and Kabsch must return the motion (up to the 1e-5 I regulariser).
    torch::manual_seed(8);
    const int64_t clusters = 8, per = 40;
    const torch::Tensor centres = torch::randn({clusters, 1, 3}, torch::kFloat64);
    const torch::Tensor src =
        (centres + 0.05 * torch::randn({clusters, per, 3}, torch::kFloat64)).view({1, -1, 3});
    const Eigen::Matrix3d R = RotationFromEulerZyxDeg(35, -20, 50);
    const torch::Tensor Rt = RotationTensor(R, torch::kFloat64);
    const torch::Tensor t = torch::tensor({0.3, -0.2, 0.1}, torch::kFloat64);
    const torch::Tensor tgt = torch::matmul(src, Rt.transpose(0, 1)) + t;
    const torch::Tensor w = torch::ones({1, clusters * per}, torch::kFloat64);
    const OverlapGmm gp = FitOverlapGmm(src, w, clusters), gq = FitOverlapGmm(tgt, w, clusters);
    const torch::Tensor moved = torch::matmul(gp.mu, Rt.transpose(0, 1)) + t;
    EXPECT_LT((moved - gq.mu).abs().max().item<double>(), 1e-6);
    const torch::Tensor onehot = torch::eye(clusters, torch::kFloat64).unsqueeze(0);
    const torch::Tensor T = SoftMatchTransform(gp.mu, onehot, gq.mu, onehot, 0.05);
    constexpr double kTol = 1e-4;  // the +1e-5 I term perturbs R by ~1e-5 / sigma_min(H)
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(T[0][r][c].item<double>(), R(r, c), kTol);
        EXPECT_NEAR(T[0][r][3].item<double>(), t[r].item<double>(), kTol);
    }
}

TEST_F(OgmmNetTest, KabschIsExactOnMatchedPointsAndNeverReflects) {
    torch::manual_seed(9);
    const torch::Tensor src = torch::randn({3, 30, 3}, torch::kFloat64);
    const Eigen::Matrix3d R = RotationFromEulerZyxDeg(-120, 40, 170);
    const torch::Tensor Rt = RotationTensor(R, torch::kFloat64);
    const torch::Tensor T = KabschTransform(src, torch::matmul(src, Rt.transpose(0, 1)) + 0.5);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(T[1][r][c].item<double>(), R(r, c), 1e-5);
        EXPECT_NEAR(T[2][r][3].item<double>(), 0.5, 1e-5);
    }
    // A mirrored target: the best proper rotation still has det +1.
    const torch::Tensor mirrored = src * torch::tensor({1.0, 1.0, -1.0}, torch::kFloat64);
    const torch::Tensor M = KabschTransform(src, mirrored);
    EXPECT_NEAR(torch::det(M.index({Slice(), Slice(0, 3), Slice(0, 3)}))[0].item<double>(), 1.0,
                1e-9);
}

TEST_F(OgmmNetTest, ZeroOverlapPointsAreIgnoredByTheGmm) {
    // Half the points (x > 0, the "non-overlapping" half) get overlap 0: their responsibilities
    // carry ~no mass and the means stay among the weighted points.
    torch::manual_seed(10);
    const torch::Tensor xyz = torch::rand({2, 600, 3}, torch::kFloat64) - 0.5;
    const torch::Tensor overlap = (xyz.select(2, 0) <= 0).to(torch::kFloat64);
    const OverlapGmm gmm = FitOverlapGmm(xyz, overlap, 16);
    const torch::Tensor row_mass = gmm.gamma.sum(2);  // [B, N]
    const double ignored = (row_mass * (1 - overlap)).sum().item<double>();
    const double kept = (row_mass * overlap).sum().item<double>();
    EXPECT_LT(ignored, 1e-3 * kept);
    EXPECT_LT(gmm.mu.select(2, 0).max().item<double>(), 0.01);
    // Control: with uniform overlap the same fit puts means on both halves.
    const OverlapGmm all = FitOverlapGmm(xyz, torch::ones_like(overlap), 16);
    EXPECT_GT(all.mu.select(2, 0).max().item<double>(), 0.2);
}

TEST_F(OgmmNetTest, LoopGmmFitEqualsTheTensorOpFit) {
    // The CPU path (plain loops) against the tensor-op path (LibTorch's logsumexp, cdist,
    // bmm), which is the same Sinkhorn k-means written op by op: in double they agree to
    // rounding; in float (the network's dtype) to float rounding amplified by 1 / eps.
    torch::manual_seed(11);
    for (const auto dtype : {torch::kFloat64, torch::kFloat32}) {
        const torch::Tensor xyz = (torch::rand({3, 257, 3}, dtype) - 0.5) * 2;
        torch::Tensor overlap = torch::rand({3, 257}, dtype);
        overlap.index_put_({0, Slice(0, 100)}, 0.0);  // points the fit must ignore
        overlap.index_put_({2}, 0.0);                 // a cloud with no overlap at all
        for (const int64_t rounds : {int64_t{1}, int64_t{10}}) {
            GmmFitOptions options;
            options.iterations = rounds;
            const OverlapGmm loops = FitOverlapGmm(xyz, overlap, 12, options);
            const OverlapGmm ops = FitOverlapGmmTensorOps(xyz, overlap, 12, options);
            const double tol = dtype == torch::kFloat64 ? 1e-9 : 2e-3;
            EXPECT_EQ(loops.gamma.scalar_type(), dtype);
            EXPECT_LT((loops.gamma - ops.gamma).abs().max().item<double>(), tol) << rounds;
            EXPECT_LT((loops.mu - ops.mu).abs().max().item<double>(), tol) << rounds;
            EXPECT_LT((loops.pi - ops.pi).abs().max().item<double>(), tol) << rounds;
        }
    }
}

// ---- forward behaviour ------------------------------------------------------------------------

PairBatch FormulaBatch(int64_t batch, int64_t n, int64_t m) {
    PairBatch pairs;
    pairs.source = testing::FormulaCloud(batch, n, 0.0);
    pairs.target = testing::FormulaCloud(batch, m, 1.0);
    pairs.T_gt = torch::eye(4).repeat({batch, 1, 1});
    pairs.T_gt.index_put_({Slice(), 0, 3}, 0.1);
    pairs.source_overlap = testing::FormulaLabels(batch, n);
    pairs.target_overlap = testing::FormulaLabels(batch, m);
    return pairs;
}

nlohmann::json SmallConfig() {
    nlohmann::json c = OgmmConfigToJson(OgmmConfig{});
    c.merge_patch({{"emb_dims", 32}, {"anchors", 8}, {"clusters", 8}, {"k", 10}});
    return c;
}

// A network of SmallConfig() with `patch` merged over it (default weights).
std::shared_ptr<RegistrationNet> SmallNet(const nlohmann::json& patch) {
    nlohmann::json config = SmallConfig();
    if (!patch.is_null()) config.merge_patch(patch);  // a null patch would replace it all
    return MakeOgmmNet(config);
}

// Two networks with identical (formula) weights, differing only in `patch`.
std::pair<std::shared_ptr<RegistrationNet>, std::shared_ptr<RegistrationNet>> TwinNets(
    const nlohmann::json& patch) {
    auto a = SmallNet({}), b = SmallNet(patch);
    testing::FormulaFill(*a);
    testing::FormulaFill(*b);
    a->eval();
    b->eval();
    return {a, b};
}

NetOutput SeededForward(RegistrationNet& net, const PairBatch& pairs, uint64_t seed) {
    torch::manual_seed(seed);  // FPS starts
    return net.Forward(pairs);
}

TEST_F(OgmmNetTest, UnequalSizesUseThePapersOverlapIndex) {
    // The code's overlap indexing needs N = M; with N != M both settings run the paper's form.
    const auto [code, paper] = TwinNets({{"fix_overlap_index", true}});
    torch::NoGradGuard no_grad;
    const PairBatch unequal = FormulaBatch(2, 60, 52);
    const NetOutput a = SeededForward(*code, unequal, 3), b = SeededForward(*paper, unequal, 3);
    EXPECT_TRUE(torch::equal(a.aux.at("overlap_source"), b.aux.at("overlap_source")));
    EXPECT_TRUE(torch::equal(a.T, b.T));
    // With N = M the flag matters.
    const PairBatch equal = FormulaBatch(2, 60, 60);
    const NetOutput c = SeededForward(*code, equal, 3), d = SeededForward(*paper, equal, 3);
    EXPECT_FALSE(torch::equal(c.aux.at("overlap_source"), d.aux.at("overlap_source")));
}

TEST_F(OgmmNetTest, EachCloudsResultIsIndependentOfTheRestOfTheBatch) {
    // Full attention has no random anchors; in eval mode the only batch coupling would be the
    // Sinkhorn stopping rule, which regbench applies per cloud.
    nlohmann::json full = SmallConfig();
    full["attention"] = "full";
    auto net = MakeOgmmNet(full);
    testing::FormulaFill(*net);
    net->eval();
    torch::NoGradGuard no_grad;
    const PairBatch both = FormulaBatch(2, 50, 50);
    const NetOutput joint = net->Forward(both);
    for (int64_t b = 0; b < 2; ++b) {
        PairBatch one;
        one.source = both.source.slice(0, b, b + 1);
        one.target = both.target.slice(0, b, b + 1);
        const NetOutput alone = net->Forward(one);
        EXPECT_LT((alone.T[0] - joint.T[b]).abs().max().item<float>(), 1e-5) << b;
    }
}

TEST_F(OgmmNetTest, OverlapOffWeighsEveryPointOneAndDropsTheOverlapLoss) {
    auto net = SmallNet({{"osp", false}});
    const PairBatch pairs = FormulaBatch(2, 40, 36);
    const NetOutput out = SeededForward(*net, pairs, 1);
    EXPECT_TRUE(torch::equal(out.aux.at("overlap_source"), torch::ones({2, 40})));
    const LossTerms terms = net->Loss(pairs, out);
    EXPECT_EQ(terms.count("ovl"), 0u);
    EXPECT_EQ(terms.count("pose"), 1u);
    EXPECT_TRUE(std::isfinite(terms.at("total").item<float>()));
}

// Sum of |grad| over the parameters whose names start with `prefix` (0 when none has a grad).
double GradientMass(torch::nn::Module& net, const std::string& prefix) {
    double mass = 0;
    for (const auto& p : net.named_parameters()) {
        if (p.key().rfind(prefix, 0) == 0 && p.value().grad().defined()) {
            mass += p.value().grad().abs().sum().item<double>();
        }
    }
    return mass;
}

TEST_F(OgmmNetTest, OverlapHeadLearnsOnlyFromTheOverlapLoss) {
    // The GMM fit sees the overlap scores detached, so with w_ovl = 0 the overlap head (proj,
    // CONV3_b, the overlap CONV3) gets no gradient while the backbone does.
    for (const double w_ovl : {0.0, 1.0}) {
        auto net = SmallNet({{"w_ovl", w_ovl}});
        const PairBatch pairs = FormulaBatch(2, 40, 40);
        const NetOutput out = SeededForward(*net, pairs, 2);
        net->Loss(pairs, out).at("total").backward();
        EXPECT_GT(GradientMass(*net, "dgcnn."), 0.0);
        for (const char* head : {"proj.", "conv3_b.", "conv3_o."}) {
            if (w_ovl == 0.0) {
                EXPECT_EQ(GradientMass(*net, head), 0.0) << head;
            } else {
                EXPECT_GT(GradientMass(*net, head), 0.0) << head;
            }
        }
    }
}

TEST_F(OgmmNetTest, LossRefusesBatchesWithoutGroundTruth) {
    auto net = SmallNet({});
    PairBatch pairs = FormulaBatch(1, 30, 30);
    const NetOutput out = SeededForward(*net, pairs, 4);
    pairs.source_overlap = torch::Tensor();
    EXPECT_THROW(net->Loss(pairs, out), std::invalid_argument);
    pairs = FormulaBatch(1, 30, 30);
    pairs.T_gt = torch::Tensor();
    EXPECT_THROW(net->Loss(pairs, out), std::invalid_argument);
    PairBatch bad;
    bad.source = torch::rand({1, 30, 2});
    bad.target = torch::rand({1, 30, 3});
    EXPECT_THROW(net->Forward(bad), std::invalid_argument);
}

// ---- parity with the PyTorch reference --------------------------------------------------------

struct ParityCase {
    nlohmann::json patch;   ///< over SmallConfig()
    int64_t n, m;           ///< source / target points (batch 2)
    bool train;             ///< BatchNorm mode
    std::vector<double> T;  ///< expected T, both clouds, row-major
    double overlap_source_sum, overlap_target_sum, mu_source_sum;
    std::map<std::string, double> loss;
};

// Expected numbers printed by scripts/ogmm_reference.py (independent PyTorch implementation,
// same formula weights and inputs; torch.manual_seed(7) right before the forward).
void ExpectParity(const ParityCase& c) {
    auto net = SmallNet(c.patch);
    testing::FormulaFill(*net);
    net->train(c.train);
    const PairBatch pairs = FormulaBatch(2, c.n, c.m);
    const NetOutput out = SeededForward(*net, pairs, 7);
    const LossTerms terms = net->Loss(pairs, out);
    const torch::Tensor T = out.T.contiguous().view({-1}).to(torch::kFloat64);
    constexpr double kTTol = 2e-4;    // float32 through SVD and Sinkhorn
    constexpr double kRelTol = 2e-4;  // sums and loss terms
    for (int64_t i = 0; i < 32; ++i) EXPECT_NEAR(T[i].item<double>(), c.T[i], kTTol) << i;
    const auto near = [&](double got, double want, const std::string& what) {
        EXPECT_NEAR(got, want, kRelTol * std::max(1.0, std::abs(want))) << what;
    };
    near(out.aux.at("overlap_source").sum().item<double>(), c.overlap_source_sum, "op");
    near(out.aux.at("overlap_target").sum().item<double>(), c.overlap_target_sum, "oq");
    near(out.aux.at("mu_source").sum().item<double>(), c.mu_source_sum, "mu");
    for (const auto& [name, value] : c.loss) near(terms.at(name).item<double>(), value, name);
}

TEST_F(OgmmNetTest, ForwardAndLossMatchThePyTorchReferenceEvalEqualSizes) {
    ExpectParity(
        {{},
         64,
         64,
         false,
         {0.802992,   0.4173341,  0.4254829,  0.0442193,  -0.4650695, 0.8852241, 0.0094315,
          -0.0818379, -0.3727115, -0.2054524, 0.9049172,  0.0676969,  0.0,       0.0,
          0.0,        1.0,        0.8556893,  0.5173247,  0.0130569,  0.1100324, -0.4962366,
          0.8274425,  -0.2628463, -0.033716,  -0.1467809, 0.2184358,  0.9647493, -0.0471186,
          0.0,        0.0,        0.0,        1.0},
         66.444091796875,
         66.44256591796875,
         -0.660700261592865,
         {{"pose", 0.08730658143758774},
          {"clu", 1.077907681465149},
          {"ovl", 0.24797582626342773},
          {"welsch", 0.02893158793449402},
          {"total", 2.1992385387420654}}});
}

TEST_F(OgmmNetTest, ForwardAndLossMatchThePyTorchReferenceTrainUnequalSizes) {
    ExpectParity({{},
                  60,
                  52,
                  true,
                  {0.8703033,  0.4385279, -0.2241999, 0.1854931,  -0.4333668, 0.8981354, 0.0744725,
                   -0.1175923, 0.2340202, 0.032347,   0.9716936,  -0.0325157, 0.0,       0.0,
                   0.0,        1.0,       0.9358908,  0.022603,   0.3515639,  0.0248869, -0.0531411,
                   0.9955783,  0.0774573, 0.0395494,  -0.3482586, -0.091174,  0.932954,  0.0927221,
                   0.0,        0.0,       0.0,        1.0},
                  59.23585891723633,
                  51.71670150756836,
                  -1.0199286937713623,
                  {{"pose", 0.05027123913168907},
                   {"clu", 0.6478817462921143},
                   {"ovl", 0.2507880926132202},
                   {"welsch", 0.02691805362701416},
                   {"total", 1.401651382446289}}});
}

TEST_F(OgmmNetTest, ForwardAndLossMatchThePyTorchReferenceFullAttentionPaperIndexNoSpe) {
    ExpectParity({{{"attention", "full"}, {"fix_overlap_index", true}, {"spe", false}},
                  48,
                  48,
                  false,
                  {0.9413139, -0.0025893, 0.3375227, -0.0277262, 0.1138663,  0.9437878,  -0.3103211,
                   0.044256,  -0.3177462, 0.3305422, 0.8886952,  -0.0447546, 0.0,        0.0,
                   0.0,       1.0,        0.9765074, 0.0369982,  -0.2122842, -0.0761002, 0.0230024,
                   0.9616229, 0.2734082,  0.0566023, 0.214253,   -0.2718681, 0.9381809,  -0.0018,
                   0.0,       0.0,        0.0,       1.0},
                  49.886802673339844,
                  49.87067413330078,
                  0.6061715483665466,
                  {{"pose", 0.04795919358730316},
                   {"clu", 0.4824341833591461},
                   {"ovl", 0.2480781078338623},
                   {"welsch", 0.019144803285598755},
                   {"total", 1.2102956771850586}}});
}

}  // namespace
}  // namespace regbench::networks
