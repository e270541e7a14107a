#include "networks/families/rgm/net.hpp"

#include <dlib/matrix.h>
#include <dlib/optimization/max_cost_assignment.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "networks/checkpoint/authors_checkpoint.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/cost.hpp"
#include "networks/families/rgm/assignment.hpp"
#include "networks/family.hpp"
#include "networks/layers/layers.hpp"
#include "tests/networks/one_thread_test.hpp"
#include "tests/networks/state_fixture.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/shell.hpp"

namespace regbench::networks {
namespace {

using torch::indexing::Slice;

class RgmTest : public OneThreadTest {};

// ---- the authors' layout --------------------------------------------------------------------

TEST_F(RgmTest, ParameterCountAndKeysAreTheAuthors) {
    // Counted with torch on networks/families/rgm/rgm_standin.py's Net (the authors' module tree):
    // 25,000,836 parameters and 138 state-dict tensors at their widths, 396,340 at width / 8.
    RgmNet net(RgmConfig{});
    EXPECT_EQ(CountParameters(net), 25000836);
    const std::map<std::string, std::vector<int64_t>> shapes = StateShapes(net);
    EXPECT_EQ(shapes.size(), 138u);
    // Shapes by hand from the authors' constructors (models/Net.py with the ModelNet40 yaml).
    const std::map<std::string, std::vector<int64_t>> theirs = {
        {"pointfeaturer.conv1.weight", {64, 6, 1, 1}},
        {"pointfeaturer.conv5.weight", {512, 512, 1, 1}},
        {"pointfeaturer.bn4.running_var", {256}},
        {"gmattend0.model.encoder.layers.0.self_attn.linears.3.weight", {1024, 1024}},
        {"gmattend0.model.decoder.layers.0.src_attn.linears.1.bias", {1024}},
        {"gmattend0.model.decoder.layers.0.sublayer.2.norm.a_2", {1024}},
        {"gmattend1.model.encoder.layers.0.feed_forward.w_1.weight", {1024, 512}},
        {"gmattend1.model.decoder.norm.b_2", {512}},
        {"gnn_layer_0.gconv.a_fc.weight", {512, 1024}},
        {"gnn_layer_1.gconv.u_fc.bias", {512}},
        {"affinity_1.A", {512, 512}},
        {"InstNorm_layer_0.weight", {1}},
        {"cross_graph_0.weight", {512, 1024}},
    };
    ExpectShapesInclude(shapes, theirs);
    RgmConfig eighth;
    eighth.width_divisor = 8;
    EXPECT_EQ(CountParameters(RgmNet(eighth)), 396340);
}

TEST_F(RgmTest, ConfigRefusesBadValuesByName) {
    EXPECT_THROW(RgmConfigFromJson({{"width_divisor", 3}}), std::invalid_argument);
    EXPECT_THROW(RgmConfigFromJson({{"heads", 3}}), std::invalid_argument);
    EXPECT_THROW(RgmConfigFromJson({{"estimate_iterations", 0}}), std::invalid_argument);
    // Unknown keys, other arches and the round trip: tests/networks/config_bounds_test.cpp.
}

// ---- pieces checked by hand -----------------------------------------------------------------

TEST_F(RgmTest, AssignmentMaximisesTheWeightOnRectangles) {
    // By hand: rows (0.9 0.8; 0.85 0.1): 0->0, 1->1 totals 1.0, 0->1, 1->0 totals 1.65.
    EXPECT_EQ(MaxWeightAssignment({0.9, 0.8, 0.85, 0.1}, 2, 2), (std::vector<int64_t>{1, 0}));
    // Three rows, two columns: the best two rows take the columns, row 1 stays free.
    EXPECT_EQ(MaxWeightAssignment({0.5, 0.6, 0.1, 0.2, 0.7, 0.3}, 3, 2),
              (std::vector<int64_t>{1, -1, 0}));
    // Two rows, three columns.
    EXPECT_EQ(MaxWeightAssignment({0.1, 0.2, 0.9, 0.3, 0.8, 0.85}, 2, 3),
              (std::vector<int64_t>{2, 1}));
    EXPECT_TRUE(MaxWeightAssignment({}, 0, 4).empty());
    EXPECT_THROW(MaxWeightAssignment({0.1, 0.2}, 2, 2), std::invalid_argument);
    EXPECT_THROW(MaxWeightAssignment({std::nan("")}, 1, 1), std::invalid_argument);
}

TEST_F(RgmTest, AssignmentTotalsEqualDlibsHungarian) {
    // The optimum's total against dlib's max_cost_assignment (the Hungarian algorithm, an
    // independent implementation) on random rectangles and a 300 x 300 Sinkhorn-like matrix;
    // weights on a 1e-6 grid, so dlib's integer costs are exact.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::lognormal_distribution<double> skewed(0.0, 1.0);
    for (const auto& [rows, cols, heavy] : std::vector<std::tuple<int64_t, int64_t, bool>>{
             {1, 1, false}, {5, 9, false}, {9, 5, false}, {40, 40, false}, {37, 61, true},
             {300, 300, true}}) {
        std::vector<double> w(static_cast<size_t>(rows * cols));
        for (double& x : w) x = std::round(1e6 * (heavy ? skewed(rng) / 20 : uniform(rng))) / 1e6;
        for (double& x : w) x = std::min(x, 1.0);
        const int64_t n = std::max(rows, cols);
        dlib::matrix<long> cost(n, n);
        cost = 0;
        for (int64_t r = 0; r < rows; ++r) {
            for (int64_t c = 0; c < cols; ++c) cost(r, c) = std::lround(w[r * cols + c] * 1e6);
        }
        const std::vector<long> theirs = dlib::max_cost_assignment(cost);
        const std::vector<int64_t> ours = MaxWeightAssignment(w, rows, cols);
        long want = 0, got = 0;
        std::vector<char> used(static_cast<size_t>(cols), 0);
        int64_t pairs = 0;
        for (int64_t r = 0; r < rows; ++r) {
            if (theirs[r] < cols) want += cost(r, theirs[r]);
            const int64_t c = ours[static_cast<size_t>(r)];
            if (c < 0) continue;
            ASSERT_LT(c, cols);
            ASSERT_FALSE(used[static_cast<size_t>(c)]) << "column " << c << " twice";
            used[static_cast<size_t>(c)] = 1;
            got += cost(r, c);
            ++pairs;
        }
        EXPECT_EQ(pairs, std::min(rows, cols)) << rows << " x " << cols;
        EXPECT_EQ(got, want) << rows << " x " << cols;
    }
}

TEST_F(RgmTest, SinkhornWithSlackKeepsRowAndColumnMassAtMostOne) {
    // After the column step every real column sums to exactly 1 with its slack entry, so its
    // real mass is < 1; rows converge to <= 1. A constant matrix (by hand): every real entry
    // equal, rows and columns at most 1.
    torch::manual_seed(1);
    const torch::Tensor s = SinkhornSlack(torch::randn({2, 7, 5}, torch::kDouble) * 3, 20).exp();
    EXPECT_LE(s.sum(2).max().item<double>(), 1.0 + 1e-9);
    EXPECT_LE(s.sum(1).max().item<double>(), 1.0 + 1e-12);
    const torch::Tensor c = SinkhornSlack(torch::zeros({1, 3, 3}, torch::kDouble), 50).exp();
    EXPECT_NEAR(c.max().item<double>(), c.min().item<double>(), 1e-12);
}

// The fused inference kernels (networks/families/rgm/kernels.hpp) against the plain LibTorch
// formulations they replace, which run when autograd records (the expected values: LibTorch's
// softmax, logsumexp and padding, an independent computation of the same formula).
TEST_F(RgmTest, FusedSinkhornMatchesTheLibTorchComposition) {
    torch::manual_seed(3);
    for (const double spread : {1.0, 3.0, 30.0}) {  // 30: rows whose entries span ~200 in log
        const torch::Tensor x = torch::randn({2, 37, 29}, torch::kDouble) * spread;
        const torch::Tensor want = SinkhornSlack(x, 20).exp();
        torch::NoGradGuard no_grad;
        const torch::Tensor got = SinkhornSlackExpInPlace(x.clone(), 20);
        EXPECT_TRUE(torch::allclose(got, want, 1e-9, 1e-12)) << spread;
        // Float, exp by FastExp (relative error < 3e-7): against the double reference.
        const torch::Tensor f = SinkhornSlackExpInPlace(x.to(torch::kFloat), 20).to(torch::kDouble);
        EXPECT_LT((f - want).abs().max().item<double>(), 2e-5) << spread;
    }
    // At the bench's size, 717 x 717 in float: the two float computations agree.
    const torch::Tensor x = torch::randn({1, 717, 717}) * 2;
    const torch::Tensor want = SinkhornSlack(x.to(torch::kDouble), 20).exp();
    torch::NoGradGuard no_grad;
    const torch::Tensor got = SinkhornSlackExpInPlace(x.clone(), 20).to(torch::kDouble);
    const torch::Tensor plain = SinkhornSlack(x, 20).exp().to(torch::kDouble);
    EXPECT_LT((got - want).abs().max().item<double>(), 1e-5);
    EXPECT_LT((plain - want).abs().max().item<double>(), 1e-5);
}

TEST_F(RgmTest, FusedAdjacencyAndAttentionMatchLibTorch) {
    torch::manual_seed(4);
    const torch::Tensor e = torch::randn({2, 16, 40}, torch::kDouble);
    const torch::Tensor gram = torch::bmm(e.transpose(1, 2), e);
    const double scale = 0.25;
    const torch::Tensor a = torch::softmax(gram * scale, -1);
    const torch::Tensor want = a / a.sum(1, true);
    {
        torch::NoGradGuard no_grad;
        EXPECT_TRUE(torch::allclose(SoftAdjacency(gram.clone(), scale), want, 1e-12, 1e-14));
        const torch::Tensor f = SoftAdjacency(gram.to(torch::kFloat), scale).to(torch::kDouble);
        EXPECT_TRUE(torch::allclose(f, want, 1e-5, 1e-7));
    }
    // The authors' LayerNorm, autograd on (LibTorch's mean and std) and off (the fused rows).
    RgmLayerNorm norm(24);
    {
        torch::NoGradGuard no_grad;
        norm->named_parameters()["a_2"].uniform_(0.5, 2.0);
        norm->named_parameters()["b_2"].uniform_(-1.0, 1.0);
    }
    const torch::Tensor rows = torch::randn({2, 30, 24}) * 3 + 1;
    const torch::Tensor normed = norm->forward(rows).detach();
    {
        torch::NoGradGuard no_grad;
        EXPECT_TRUE(torch::allclose(norm->forward(rows), normed, 1e-5, 1e-6));
    }
    // Attention: the module with autograd on (LibTorch's softmax) and off (the fused rows).
    RgmAttention attention(32, 4);
    const torch::Tensor x = torch::randn({2, 50, 32}), memory = torch::randn({2, 60, 32});
    const torch::Tensor plain = attention->forward(x, memory).detach();
    torch::NoGradGuard no_grad;
    EXPECT_TRUE(torch::allclose(attention->forward(x, memory), plain, 1e-4, 1e-6));
}

TEST_F(RgmTest, MatchWithoutAutogradMatchesMatchWithIt) {
    // The whole match (rgm-small's widths) through the fused kernels and through LibTorch's
    // compositions, in double so that only the formulations differ.
    RgmConfig c;
    c.width_divisor = 8;
    RgmNet net(c);
    net.to(torch::kDouble);
    net.eval();
    torch::manual_seed(5);
    const torch::Tensor src = torch::rand({1, 90, 3}, torch::kDouble) - 0.5;
    const torch::Tensor tgt = torch::rand({1, 80, 3}, torch::kDouble) - 0.5;
    const torch::Tensor plain = net.Match(src, tgt).detach();
    torch::NoGradGuard no_grad;
    const torch::Tensor fused = net.Match(src, tgt);
    EXPECT_TRUE(torch::allclose(fused, plain, 1e-9, 1e-12))
        << (fused - plain).abs().max().item<double>();
}

TEST_F(RgmTest, WeightedRigidRecoversAMotionExactly) {
    torch::manual_seed(2);
    const torch::Tensor P = torch::rand({1, 12, 3}, torch::kDouble) - 0.5;
    torch::Tensor T = torch::eye(4, torch::kDouble).unsqueeze(0);
    const double a = 0.7;  // about z, by hand
    T[0][0][0] = std::cos(a);
    T[0][0][1] = -std::sin(a);
    T[0][1][0] = std::sin(a);
    T[0][1][1] = std::cos(a);
    T[0][0][3] = 0.3;
    T[0][2][3] = -0.1;
    const torch::Tensor Q =
        torch::bmm(P, T.index({Slice(), Slice(0, 3), Slice(0, 3)}).transpose(1, 2)) +
        T.index({Slice(), Slice(0, 3), 3}).unsqueeze(1);
    // Weights sum to 12; the authors' + 1e-5 shrinks the centroids by 12 / (12 + 1e-5).
    const torch::Tensor est = WeightedRigid(P, Q, torch::ones({1, 12}, torch::kDouble));
    EXPECT_TRUE(torch::allclose(est, T, 0, 1e-5)) << est;
    EXPECT_TRUE(torch::equal(WeightedRigid(P, Q, torch::zeros({1, 12}, torch::kDouble)),
                             torch::eye(4, torch::kDouble).unsqueeze(0)));
}

// ---- parity with the PyTorch stand-in --------------------------------------------------------

TEST_F(RgmTest, ImportedStandInMatchesItsForwardPipelineAndLoss) {
    // Written at test time by Debian's python3-torch and python3-scipy (`rgm_standin.py write
    // DIR 8`): the authors' file layout (torch.save of the state dict, zip) at width / 8 with
    // seeded float32 weights, and the stand-in's own float64 results on two pairs (40 + 40
    // points, and 48 + 35: N != M, where the authors' code fails): the first match's soft
    // correspondence, the loss, and the whole test-time pipeline's pairs and transform (scipy's
    // linear_sum_assignment there, regbench's shortest augmenting paths here).
    const char* env = std::getenv("REGBENCH_SOURCE_DIR");
    const std::string source = env != nullptr ? env : ".";
    const std::filesystem::path dir = regbench::testing::FreshTempDir("rgm_standin");
    const auto [rc, out] = regbench::testing::RunShell(
        "OMP_NUM_THREADS=1 /usr/bin/python3 " + source +
        "/networks/families/rgm/rgm_standin.py write " + dir.string() + " 8 2>&1");
    ASSERT_EQ(rc, 0) << out;
    nlohmann::json expected;
    std::ifstream(dir / "expected.json") >> expected;
    ImportOptions options;
    options.from = "rgm";
    ImportAuthorsCheckpoint((dir / "rgm.pth").string(), (dir / "imported").string(), options);
    const auto imported = LoadNetFromCheckpoint((dir / "imported").string());
    EXPECT_EQ(imported->Config().at("width_divisor"), 8);
    auto* net = dynamic_cast<RgmNet*>(imported.get());
    ASSERT_NE(net, nullptr);
    net->to(torch::kDouble);
    net->eval();
    torch::NoGradGuard no_grad;
    for (const auto& c : expected.at("cases")) {
        SCOPED_TRACE(c.at("name").get<std::string>());
        const int64_t n = static_cast<int64_t>(c.at("source").size());
        const int64_t m = static_cast<int64_t>(c.at("target").size());
        PairBatch pair;
        pair.source = TensorFromJson(c.at("source")).view({1, n, 3});
        pair.target = TensorFromJson(c.at("target")).view({1, m, 3});
        pair.T_gt = TensorFromJson(c.at("T_gt")).view({1, 4, 4});
        const torch::Tensor s = net->Match(pair.source, pair.target);
        const torch::Tensor want_s = TensorFromJson(c.at("s")).view({1, n, m});
        EXPECT_LT((s - want_s).abs().max().item<double>(), 1e-9);
        NetOutput soft;
        soft.aux["s"] = s;
        EXPECT_NEAR(net->Loss(pair, soft).at("total").item<double>(), c.at("loss").get<double>(),
                    1e-8);
        const NetOutput result = net->Forward(pair);
        EXPECT_EQ(result.aux.at("correspondence").sum().item<double>(),
                  c.at("pairs").get<double>());
        const torch::Tensor want_T = TensorFromJson(c.at("T")).view({1, 4, 4});
        // Rotation and translation: the parity bound asked for is 1e-4; they agree to 1e-9.
        EXPECT_LT((result.T - want_T).abs().max().item<double>(), 1e-9)
            << result.T << "\n"
            << want_T;
    }
    std::filesystem::remove_all(dir);
}

TEST_F(RgmTest, FullWidthRunsOnCloudsOfDifferentSizesAndFewPoints) {
    // The authors' widths on 30 + 23 points (their code fails for N != M) and a 12-point
    // target (fewer than k = 20: every point a neighbour): finite rigid transforms.
    torch::manual_seed(4);
    RgmNet net(RgmConfig{});
    net.eval();
    for (const int64_t m : {23, 12}) {
        PairBatch pair;
        pair.source = torch::rand({1, 30, 3}) - 0.5;
        pair.target = torch::rand({1, m, 3}) - 0.5;
        const NetOutput out = net.Forward(pair);
        ASSERT_TRUE(torch::isfinite(out.T).all().item<bool>());
        const torch::Tensor R = out.T[0].index({Slice(0, 3), Slice(0, 3)}).to(torch::kDouble);
        EXPECT_TRUE(torch::allclose(torch::mm(R, R.t()), torch::eye(3, torch::kDouble), 0, 1e-5));
    }
    PairBatch bad;
    bad.source = torch::rand({1, 30, 2});
    bad.target = torch::rand({1, 30, 3});
    EXPECT_THROW(net.Forward(bad), std::invalid_argument);
}

TEST_F(RgmTest, LossIsFiniteAndTrainsEveryPart) {
    torch::manual_seed(3);
    RgmConfig config;
    config.width_divisor = 16;
    RgmNet net(config);
    net.train();
    PairBatch batch;
    batch.source = torch::rand({2, 40, 3}) - 0.5;
    batch.T_gt = torch::eye(4).repeat({2, 1, 1});
    batch.target = batch.source.flip(1) + 0.001;
    const NetOutput out = net.Forward(batch);
    const torch::Tensor total = net.Loss(batch, out).at("total");
    ASSERT_TRUE(std::isfinite(total.item<double>()));
    total.backward();
    for (const std::string key : {"pointfeaturer.conv1.weight",
                                  "gmattend0.model.encoder.layers.0.self_attn.linears.0.weight",
                                  "gnn_layer_1.gconv.a_fc.weight", "affinity_1.A",
                                  "InstNorm_layer_1.weight", "cross_graph_0.weight"}) {
        const torch::Tensor g = net.named_parameters()[key].grad();
        ASSERT_TRUE(g.defined()) << key;
        EXPECT_GT(g.abs().sum().item<double>(), 0.0) << key;
    }
}

TEST_F(RgmTest, MacsAreTheLayersProductsCountedByHand) {
    // One match at width / 8 (node 64, edge 64, d0 128, gnn 64, ff 128) on 30 + 30 points, k 20:
    // dgcnn per cloud 30*20*(6*8 + 8*8 + 8*16 + 16*32) + 30*64*64 + 3*30*30 = 576,780;
    // transformer layer d: 4 passes of 4*30*d^2 + 2*900*d + 2*30*d*128, decoders also
    // 2*30*d^2 + 2*30*d^2 + 2*900*d: d=128 -> 4*(1966080+230400+983040) + 2*(1966080+230400)
    // = 17,111,040; d=64 -> 4*(491520+115200+491520) + 2*(491520+115200) = 5,606,400.
    RgmConfig c;
    c.width_divisor = 8;
    c.estimate_iterations = 1;
    c.cycle = false;
    const auto macs = RgmForwardMacs(c, 30, 30);
    EXPECT_EQ(macs.at("dgcnn"), 2 * 576780);
    EXPECT_EQ(macs.at("transformer"), 17111040 + 5606400);
    EXPECT_EQ(macs.at("adjacency"), 1800 * 128 + 1800 * 64);
    EXPECT_EQ(macs.at("gconv"), 2 * 60 * 128 * 64 + 1800 * 64 + 2 * 60 * 64 * 64 + 1800 * 64);
    EXPECT_EQ(macs.at("affinity"), 2 * (30 * 64 * 64 + 900 * 64));
    EXPECT_EQ(macs.at("cross_graph"), 2 * 900 * 64 + 60 * 2 * 64 * 64);
    // The default pipeline: two rounds both ways, four matches.
    c.estimate_iterations = 2;
    c.cycle = true;
    EXPECT_EQ(RgmForwardMacs(c, 30, 30).at("dgcnn"), 4 * 2 * 576780);
    EXPECT_THROW(FindFamily("rgm").forward_cost(ToJson(c), 0, 30), std::invalid_argument);
}

}  // namespace
}  // namespace regbench::networks
