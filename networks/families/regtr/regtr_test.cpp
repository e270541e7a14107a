#include "networks/families/regtr/net.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "networks/checkpoint/authors_checkpoint.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/cost.hpp"
#include "networks/family.hpp"
#include "networks/layers/layers.hpp"
#include "tests/networks/one_thread_test.hpp"
#include "tests/networks/state_fixture.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/shell.hpp"

namespace regbench::networks {
namespace {

using torch::indexing::Slice;

class RegtrTest : public OneThreadTest {};

std::string SourceDir() {
    const char* env = std::getenv("REGBENCH_SOURCE_DIR");
    return env != nullptr ? env : ".";
}

torch::Tensor Rows(const nlohmann::json& j) {
    std::vector<double> v;
    for (const auto& row : j) {
        for (const auto& x : row) v.push_back(x.get<double>());
    }
    return torch::tensor(v, torch::kDouble).view({static_cast<int64_t>(j.size()), -1});
}

// ---- the authors' layout --------------------------------------------------------------------

TEST_F(RegtrTest, ParameterCountAndKeysAreTheAuthors) {
    // 11,488,018: `/usr/bin/python3 networks/families/regtr/regtr_standin.py count` (torch counts
    // the stand-in's modules, which have the authors' layout; the authors' REGTR with the ModelNet
    // config, random weights, gives about 11.5 M).
    RegtrNet net(RegtrConfig{});
    EXPECT_EQ(CountParameters(net) + 6 * 15 * 3, 11488018);  // kernel points: buffers here
    const std::map<std::string, std::vector<int64_t>> shapes = StateShapes(net);
    const std::map<std::string, std::vector<int64_t>> theirs = {
        {"kpf_encoder.encoder_blocks.0.KPConv.weights", {15, 1, 256}},
        {"kpf_encoder.encoder_blocks.0.KPConv.kernel_points", {15, 3}},
        {"kpf_encoder.encoder_blocks.1.unary1.mlp.weight", {128, 256}},
        {"kpf_encoder.encoder_blocks.1.unary_shortcut.mlp.weight", {512, 256}},
        {"kpf_encoder.encoder_blocks.3.KPConv.weights", {15, 128, 128}},
        {"kpf_encoder.encoder_blocks.4.unary2.mlp.weight", {1024, 256}},
        {"kpf_encoder.encoder_blocks.5.KPConv.weights", {15, 256, 256}},
        {"feat_proj.weight", {256, 1024}},
        {"transformer_encoder.layers.5.self_attn.in_proj_weight", {768, 256}},
        {"transformer_encoder.layers.0.multihead_attn.out_proj.bias", {256}},
        {"transformer_encoder.layers.3.linear1.weight", {1024, 256}},
        {"transformer_encoder.layers.2.norm3.bias", {256}},
        {"transformer_encoder.norm.weight", {256}},
        {"correspondence_decoder.coor_mlp.4.weight", {3, 256}},
        {"correspondence_decoder.conf_logits_decoder.weight", {1, 256}},
        {"feature_criterion.W", {256, 256}},
        {"feature_criterion_un.W", {256, 256}},
    };
    ExpectShapesInclude(shapes, theirs);
    // Blocks 2, 3 and 5 keep their width: no unary_shortcut (the authors' nn.Identity).
    EXPECT_FALSE(shapes.count("kpf_encoder.encoder_blocks.2.unary_shortcut.mlp.weight"));
    EXPECT_FALSE(shapes.count("kpf_encoder.encoder_blocks.0.unary1.mlp.weight"));
}

TEST_F(RegtrTest, ConfigRefusesBadValuesByName) {
    EXPECT_THROW(RegtrConfigFromJson({{"d_embed", 250}}), std::invalid_argument);  // 8 heads
    EXPECT_THROW(RegtrConfigFromJson({{"num_encoder_layers", 0}}), std::invalid_argument);
    // Unknown keys, other arches and the round trip: tests/networks/config_bounds_test.cpp.
}

// ---- subsampling and neighbours, by hand ----------------------------------------------------

TEST_F(RegtrTest, GridSubsamplingAveragesVoxelsInIntegerOrder) {
    // dl = 1: (0.2, 0.2, 0.2) and (0.4, 0.6, 0.8) share voxel (0, 0, 0); (-0.5, 0, 0) is in
    // (-1, 0, 0) (floor, not truncation); (0.1, 0.1, 1.5) in (0, 0, 1). Sorted: (-1, 0, 0),
    // (0, 0, 0), (0, 0, 1).
    const torch::Tensor p = torch::tensor(
        {{0.2, 0.2, 0.2}, {0.1, 0.1, 1.5}, {-0.5, 0.0, 0.0}, {0.4, 0.6, 0.8}}, torch::kDouble);
    const torch::Tensor want =
        torch::tensor({{-0.5, 0.0, 0.0}, {0.3, 0.4, 0.5}, {0.1, 0.1, 1.5}}, torch::kDouble);
    EXPECT_TRUE(torch::allclose(GridSubsample(p, 1.0), want, 1e-12, 1e-12));
    EXPECT_THROW(GridSubsample(torch::zeros({0, 3}), 1.0), std::invalid_argument);
}

TEST_F(RegtrTest, RadiusNeighboursAreStrictInIndexOrderAndCapped) {
    // Supports on the x axis at 0, 1, 2, 3, 0.5; query at 0, radius 1.5: 0 (0), 1 (1), 4
    // (0.5) are within, 2 and 3 are not; in index order 0, 1, 4; capped at 2: 0, 1. Radius
    // exactly 1 excludes the point at 1 (strict).
    const torch::Tensor s = torch::tensor(
        {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {2.0, 0.0, 0.0}, {3.0, 0.0, 0.0}, {0.5, 0.0, 0.0}},
        torch::kDouble);
    const torch::Tensor q = torch::zeros({1, 3}, torch::kDouble);
    EXPECT_TRUE(
        torch::equal(RadiusNeighbors(q, s, 1.5, 4), torch::tensor({{0, 1, 4, 5}}, torch::kLong)));
    EXPECT_TRUE(torch::equal(RadiusNeighbors(q, s, 1.5, 2), torch::tensor({{0, 1}}, torch::kLong)));
    EXPECT_TRUE(
        torch::equal(RadiusNeighbors(q, s, 1.0, 3), torch::tensor({{0, 4, 5}}, torch::kLong)));
}

TEST_F(RegtrTest, WeightedKabschRecoversAMotionAndIgnoresZeroWeights) {
    // Hand: a 90-degree turn about z and t = (1, 2, 3) on four points; a fifth, wrong pair has
    // weight 0.
    const torch::Tensor a = torch::tensor(
        {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}, {5.0, 5.0, 5.0}},
        torch::kDouble);
    const torch::Tensor b = torch::tensor(
        {{1.0, 2.0, 3.0}, {1.0, 3.0, 3.0}, {0.0, 2.0, 3.0}, {1.0, 2.0, 4.0}, {-9.0, 0.0, 0.0}},
        torch::kDouble);
    const torch::Tensor w = torch::tensor({1.0, 0.5, 0.5, 1.0, 0.0}, torch::kDouble);
    const torch::Tensor want = torch::tensor(
        {{0.0, -1.0, 0.0, 1.0}, {1.0, 0.0, 0.0, 2.0}, {0.0, 0.0, 1.0, 3.0}, {0.0, 0.0, 0.0, 1.0}},
        torch::kDouble);
    EXPECT_TRUE(torch::allclose(WeightedKabsch(a, b, w), want, 1e-9, 1e-9));
}

// ---- parity with the PyTorch stand-in -------------------------------------------------------

TEST_F(RegtrTest, ForwardMatchesTheStandInAndTheImportReadsTheirFile) {
    // `regtr_standin.py write DIR`: per case, the stand-in with seeded random weights (kernel
    // points included) saved by torch.save as {"state_dict": ..., "epoch": 0}, two clouds and
    // the stand-in's float64 transform. Here: the file read by the reader the authors' files go
    // through, loaded strictly into a float64 RegtrNet, same clouds; and the import command's
    // path (float32 checkpoint) on the N != M case.
    const std::filesystem::path dir = testing::FreshTempDir("regtr_parity");
    const auto [rc, out] = testing::RunShell("/usr/bin/python3 " + SourceDir() +
                                             "/networks/families/regtr/regtr_standin.py write " +
                                             dir.string() + " 2>&1");
    ASSERT_EQ(rc, 0) << out;
    const nlohmann::json cases = nlohmann::json::parse(testing::ReadBytes(dir / "cases.json"));
    for (const auto& [name, c] : cases.items()) {
        SCOPED_TRACE(name);
        const std::string pth = (dir / (name + ".pth")).string();
        const TorchSaveContents contents = ReadTorchSaveFile(pth);
        EXPECT_EQ(contents.wrapper, "state_dict");
        RegtrConfig config;
        if (name != "modelnet") {
            config.first_feats_dim = 64;
            config.d_embed = 64;
            config.d_feedforward = 128;
            config.num_encoder_layers = 2;
        }
        RegtrNet net(config);
        net.to(torch::kDouble);
        LoadStrictStateDict(net, contents.tensors, pth, "REGTR");
        net.eval();
        torch::NoGradGuard no_grad;
        PairBatch pair;
        pair.source = Rows(c.at("source")).unsqueeze(0);
        pair.target = Rows(c.at("target")).unsqueeze(0);
        const NetOutput o = net.Forward(pair);
        EXPECT_EQ(o.aux.at("src_kp_0").size(0), c.at("superpoints")[0].get<int64_t>());
        EXPECT_EQ(o.aux.at("tgt_kp_0").size(0), c.at("superpoints")[1].get<int64_t>());
        const torch::Tensor want = Rows(c.at("T"));
        const double rot_err =
            (o.T[0].index({Slice(0, 3), Slice(0, 3)}) - want.index({Slice(0, 3), Slice(0, 3)}))
                .abs()
                .max()
                .item<double>();
        const double trans_err = (o.T[0].index({Slice(0, 3), 3}) - want.index({Slice(0, 3), 3}))
                                     .abs()
                                     .max()
                                     .item<double>();
        EXPECT_LT(rot_err, 1e-4);
        EXPECT_LT(trans_err, 1e-4);
        // A non-trivial pose: the random network's estimate is far from the identity.
        EXPECT_GT((want.index({Slice(0, 3), Slice(0, 3)}) - torch::eye(3, torch::kDouble))
                      .abs()
                      .max()
                      .item<double>(),
                  0.1);
        if (name == "modelnet") continue;
        // The import command's path: float32 weights in a regbench checkpoint.
        ImportOptions options;
        options.from = "regtr";
        ImportAuthorsCheckpoint(pth, (dir / "imported").string(), options);
        const auto imported = LoadNetFromCheckpoint((dir / "imported").string());
        EXPECT_EQ(imported->Config().at("d_embed"), 64);
        EXPECT_EQ(imported->Config().at("num_encoder_layers"), 2);
        EXPECT_EQ(imported->Config().at("nhead"), 8);
        PairBatch pair32;
        pair32.source = pair.source.to(torch::kFloat);
        pair32.target = pair.target.to(torch::kFloat);
        const torch::Tensor T32 = imported->Forward(pair32).T.to(torch::kDouble)[0];
        EXPECT_LT((T32 - want).abs().max().item<double>(), 1e-3) << T32 << want;
    }
    std::filesystem::remove_all(dir);
}

// ---- training and odd inputs ----------------------------------------------------------------

/// A config of reduced widths, 2 layers: first_feats_dim F, d_embed d, heads, d_feedforward ff.
RegtrConfig Widths(int F, int d, int heads, int ff) {
    RegtrConfig c;
    c.first_feats_dim = F;
    c.d_embed = d;
    c.nhead = heads;
    c.d_feedforward = ff;
    c.num_encoder_layers = 2;
    return c;
}

/// regtr-small's widths (networks/families/regtr/family.cpp).
RegtrConfig SmallWidths() { return Widths(64, 64, 4, 128); }

RegtrConfig Tiny() { return Widths(16, 12, 2, 16); }

torch::Tensor Patch(int64_t n, double phase) {
    const torch::Tensor u = torch::linspace(-0.2, 0.2, n, torch::kFloat);
    const torch::Tensor v = torch::sin(u * 37.0 + phase) * 0.2;
    return torch::stack({u, v, 0.05 * torch::cos(u * 11.0)}, 1);
}

TEST_F(RegtrTest, LossIsFiniteAndReachesEveryPart) {
    torch::manual_seed(3);
    RegtrNet net(Tiny());
    net.train();
    PairBatch batch;
    batch.source = torch::stack({Patch(60, 0.0), Patch(60, 1.0)});
    batch.target = torch::stack({Patch(47, 0.3), Patch(47, 0.7)});  // N != M
    batch.T_gt = torch::eye(4).repeat({2, 1, 1});
    batch.T_gt.index_put_({Slice(), 0, 3}, 0.01);
    const NetOutput out = net.Forward(batch);
    const LossTerms terms = net.Loss(batch, out);
    for (const char* k : {"overlap", "feature", "corr", "total"}) {
        ASSERT_TRUE(std::isfinite(terms.at(k).item<double>())) << k;
    }
    EXPECT_GT(terms.at("overlap").item<double>(), 0.0);
    EXPECT_GT(terms.at("corr").item<double>(), 0.0);
    terms.at("total").backward();
    for (const auto& p : net.named_parameters()) {
        const std::string& key = p.key();
        if (key.find("feature_criterion_un") != std::string::npos) continue;  // weight 0
        ASSERT_TRUE(p.value().grad().defined()) << key;
        EXPECT_TRUE(std::isfinite(p.value().grad().abs().sum().item<double>())) << key;
    }
}

TEST_F(RegtrTest, TinyAndUnequalCloudsGiveATransform) {
    RegtrNet net(Tiny());
    net.eval();
    torch::NoGradGuard no_grad;
    for (const auto& [n, m] : std::vector<std::pair<int64_t, int64_t>>{{1, 1}, {1, 5}, {40, 3}}) {
        PairBatch pair;
        pair.source = Patch(n, 0.0).unsqueeze(0);
        pair.target = Patch(m, 0.5).unsqueeze(0);
        const NetOutput o = net.Forward(pair);
        ASSERT_EQ(o.T.sizes(), (std::vector<int64_t>{1, 4, 4}));
        EXPECT_TRUE(torch::isfinite(o.T).all().item<bool>()) << n << " " << m;
    }
    PairBatch bad;
    bad.source = torch::zeros({1, 0, 3});
    bad.target = torch::zeros({1, 5, 3});
    EXPECT_THROW(net.Forward(bad), std::invalid_argument);
}

// ---- the fused inference kernels (kernels.hpp) against the LibTorch composition ---------------

/// One KPConv both ways: with autograd (the LibTorch composition) and without (the fused loop).
std::pair<torch::Tensor, torch::Tensor> KpconvBothWays(RegtrKpconv& conv, const torch::Tensor& q,
                                                       const torch::Tensor& s,
                                                       const torch::Tensor& nb,
                                                       const torch::Tensor& x) {
    torch::Tensor composed;
    {
        torch::AutoGradMode grad(true);
        composed = conv->forward(q, s, nb, x).detach();
    }
    torch::NoGradGuard no_grad;
    return {composed, conv->forward(q, s, nb, x)};
}

TEST_F(RegtrTest, FusedKpconvEqualsTheLibTorchComposition) {
    // Random clouds, radius neighbours with shadow columns (rows not full), features of mixed
    // sign (some rows sum to <= 0 and are not counted), a strided case (queries != supports) and
    // the first block's single channel. Reference: the LibTorch composition of the same module
    // (gathers, [Q, H, K, 3] influences, bmm, kernel GEMM), run with autograd on.
    torch::manual_seed(11);
    for (const auto dtype : {torch::kDouble, torch::kFloat}) {
        SCOPED_TRACE(dtype == torch::kDouble ? "double" : "float");
        const double tol = dtype == torch::kDouble ? 1e-12 : 2e-5;
        const torch::Tensor s = (torch::rand({300, 3}, torch::kDouble) - 0.5).to(dtype);
        const torch::Tensor q = s.index({Slice(0, 120)}).clone();
        for (const auto& [in, nb] :
             {std::pair<int64_t, torch::Tensor>{1, RadiusNeighbors(s, s, 0.15, 50)},
              {16, RadiusNeighbors(q, s, 0.15, 12)},
              {16, RadiusNeighbors(s, s, 0.2, 50)}}) {
            RegtrKpconv conv(in, 8, 0.15, 0.1);
            conv->to(dtype);
            const torch::Tensor x =
                in == 1 ? torch::ones({300, 1}, dtype) : torch::randn({300, in}, dtype);
            const torch::Tensor qq = nb.size(0) == q.size(0) ? q : s;
            ASSERT_TRUE((nb == s.size(0)).any().item<bool>());  // some shadow entries
            const auto [want, got] = KpconvBothWays(conv, qq, s, nb, x);
            ASSERT_EQ(got.sizes(), want.sizes());
            const double scale = want.abs().max().item<double>();
            EXPECT_GT(scale, 0.0);
            EXPECT_LT((got - want).abs().max().item<double>(), tol * scale);
        }
    }
}

TEST_F(RegtrTest, ForwardWithoutAutogradEqualsTheLibTorchComposition) {
    // A regtr-small-like network (widths / 8, d 64, 4 heads, 2 layers) on 400 + 350 points, in
    // double: every output of the inference path (fused kernels) against the same forward with
    // autograd on (the LibTorch composition throughout).
    torch::manual_seed(5);
    RegtrNet net(SmallWidths());
    net.to(torch::kDouble);
    net.eval();
    PairBatch pair;
    pair.source = (torch::rand({1, 400, 3}, torch::kDouble) - 0.5);
    pair.target = (torch::rand({1, 350, 3}, torch::kDouble) - 0.5);
    NetOutput composed;
    {
        torch::AutoGradMode grad(true);
        composed = net.Forward(pair);
    }
    torch::NoGradGuard no_grad;
    const NetOutput fused = net.Forward(pair);
    EXPECT_LT((fused.T - composed.T).abs().max().item<double>(), 1e-9);
    for (const auto& [key, want] : composed.aux) {
        SCOPED_TRACE(key);
        const torch::Tensor got = fused.aux.at(key);
        ASSERT_EQ(got.sizes(), want.sizes());
        EXPECT_LT(
            (got.to(torch::kDouble) - want.detach().to(torch::kDouble)).abs().max().item<double>(),
            1e-9);
    }
}

TEST_F(RegtrTest, MacsAreTheLayersProductsCountedByHand) {
    // regtr-small-like widths F = 64, d = 64, ff = 128, 2 layers on 717 + 717 points (700
    // superpoints each), neighbours 50, 15 kernel points, by hand:
    //  kpconv per cloud: 717 (15*50*1 + 15*1*32) + 2 * 717 (15*50*16 + 15*16*16)
    //                    + 700 (15*50*16 + 15*16*16) + 2 * 700 (15*50*32 + 15*32*32)
    //  feedforward: 2 layers * 2 * 64 * 128 * 1400.
    const RegtrConfig c = SmallWidths();
    const auto macs = RegtrForwardMacs(c, 717, 717);
    const int64_t kp = 717LL * (750 + 480) + 2 * 717LL * (12000 + 3840) + 700LL * (12000 + 3840) +
                       2 * 700LL * (24000 + 15360);
    EXPECT_EQ(macs.at("kpconv"), 2 * kp);
    EXPECT_EQ(macs.at("feedforward"), 2LL * 2 * 64 * 128 * 1400);
    EXPECT_THROW(FindFamily("regtr").forward_cost(ToJson(c), 0, 717), std::invalid_argument);
}

}  // namespace
}  // namespace regbench::networks
