#include "networks/families/omnet/net.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "networks/checkpoint/authors_checkpoint.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/cost.hpp"
#include "networks/family.hpp"
#include "networks/layers/layers.hpp"
#include "tests/networks/formula_fixture.hpp"
#include "tests/networks/one_thread_test.hpp"
#include "tests/networks/state_fixture.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/shell.hpp"

namespace regbench::networks {
namespace {

using torch::indexing::Slice;

class OmnetTest : public OneThreadTest {};

// ---- the authors' layout --------------------------------------------------------------------

TEST_F(OmnetTest, ParameterCountAndKeysAreTheAuthors) {
    // Counted with torch from the authors' modules (hxwork/OMNet_Pytorch model/module.py, four
    // of each): encoder 151,680, fusion 3,743,232, decoder 462,338, regression 9,057,287 per
    // iteration, 53,658,148 in all; their state dict holds 109 tensors per iteration.
    OmnetNet net(OmnetConfig{});
    EXPECT_EQ(CountParameters(net), 53658148);
    const std::map<std::string, std::vector<int64_t>> shapes = StateShapes(net);
    EXPECT_EQ(shapes.size(), 4u * 109u);
    const std::map<std::string, std::vector<int64_t>> theirs = {
        {"encoder.0.conv_block1.0.weight", {64, 3, 1}},
        {"encoder.3.conv_block5.1.running_var", {1024}},
        {"fusion.1.conv_block1.0.weight", {1024, 2112, 1}},
        {"fusion.2.conv_block3.1.num_batches_tracked", {}},
        {"decoder.0.conv_block4.0.bias", {2}},
        {"regression.2.fc_block1.0.weight", {2048, 3072}},
        {"regression.3.fc_block4.1.weight", {256}},
        {"regression.0.final_fc.0.weight", {7, 256}},
    };
    ExpectShapesInclude(shapes, theirs);
    // A width divisor of 8: every hidden width / 8, the input (3) and outputs (2, 7) kept.
    OmnetConfig small;
    small.width_divisor = 8;
    OmnetNet eighth(small);
    const auto eighth_shapes = StateShapes(eighth);
    EXPECT_EQ(eighth_shapes.at("fusion.1.conv_block1.0.weight"),
              (std::vector<int64_t>{128, 264, 1}));
    EXPECT_EQ(eighth_shapes.at("regression.0.final_fc.0.weight"), (std::vector<int64_t>{7, 32}));
}

TEST_F(OmnetTest, ConfigRefusesBadValuesByName) {
    EXPECT_THROW(OmnetConfigFromJson({{"width_divisor", 3}}), std::invalid_argument);
    EXPECT_THROW(OmnetConfigFromJson({{"iterations", 0}}), std::invalid_argument);
    // Unknown keys, other arches and the round trip: tests/networks/config_bounds_test.cpp.
}

// ---- quaternions, checked by hand -----------------------------------------------------------

TEST_F(OmnetTest, QuaternionsComposeAsRotationsDo) {
    // q = (cos 45, sin 45, 0, 0): 90 degrees about x; p = (cos 45, 0, 0, sin 45): 90 about z.
    const double h = std::sqrt(0.5);
    const torch::Tensor qx = torch::tensor({{h, h, 0.0, 0.0, 1.0, 0.0, 0.0}}, torch::kDouble);
    const torch::Tensor qz = torch::tensor({{h, 0.0, 0.0, h, 0.0, 2.0, 0.0}}, torch::kDouble);
    // Rx(90) = [[1,0,0],[0,0,-1],[0,1,0]] (hand).
    const torch::Tensor Rx = QuaternionToMatrix(qx.index({Slice(), Slice(0, 4)}))[0];
    EXPECT_TRUE(torch::allclose(
        Rx, torch::tensor({{1.0, 0.0, 0.0}, {0.0, 0.0, -1.0}, {0.0, 1.0, 0.0}}, torch::kDouble),
        1e-12, 1e-12));
    // First x (t = (1, 0, 0)), then z (t = (0, 2, 0)): R = Rz Rx, t = Rz (1, 0, 0) + (0, 2, 0) =
    // (0, 1, 0) + (0, 2, 0) = (0, 3, 0).
    const torch::Tensor both = ComposePoses(qx, qz);
    const torch::Tensor R = QuaternionToMatrix(both.index({Slice(), Slice(0, 4)}))[0];
    const torch::Tensor Rz = QuaternionToMatrix(qz.index({Slice(), Slice(0, 4)}))[0];
    EXPECT_TRUE(torch::allclose(R, torch::matmul(Rz, Rx), 1e-12, 1e-12));
    EXPECT_TRUE(torch::allclose(both.index({0, Slice(4, 7)}),
                                torch::tensor({0.0, 3.0, 0.0}, torch::kDouble), 1e-12, 1e-12));
}

// ---- parity with the PyTorch stand-in -------------------------------------------------------

struct ParityCase {
    const char* name;
    int divisor;
    int64_t batch, n, m;
    std::vector<double> overlap_bias;   // added to decoder.{1,2}.conv_block4.0.bias[1]
    std::vector<double> T;              // [batch, 4, 4] row-major
    std::vector<double> mask_fraction;  // source masks of iterations 0..3, then the target's
    std::map<std::string, double> loss;
};

// From `/usr/bin/python3 networks/families/omnet/omnet_standin.py expected` (PyTorch 1.13,
// float64): the stand-in's forward with the formula weights, and its overlap biases (which make the
// masks of iterations 2 and 3 mixed instead of all 0 or all 1). On full_width the authors' own
// OMNet (model/net.py on the CPU, float32: `omnet_standin.py authors DIR`) gives T within 4.6e-5 of
// these float64 values. Their code cannot run divisor8_different (N != M).
const ParityCase kCases[] = {
    {"full_width",
     1,
     1,
     40,
     40,
     {-0.2780781615849659, -0.2568450773908623},
     {0.093825043294, 0.66987974846, -0.736517470162, -0.372973399097, -0.523442555458,
      0.662472473099, 0.535852697596, -0.41291399192, 0.846879420217, 0.33524818417, 0.412800075853,
      -0.236699503897, 0.0, 0.0, 0.0, 1.0},
     {1.0, 1.0, 0.5, 0.5, 1.0, 1.0, 0.4, 0.4},
     {{"overlap_2", 0.6889278058},
      {"overlap_3", 0.8077682661},
      {"quat_3", 0.3780553778},
      {"trans_3", 0.433417146},
      {"total", 4.6806826625}}},
    {"divisor8_same",
     8,
     2,
     60,
     60,
     {0.04189756866124181, 0.04428070264229958},
     {-0.646023489304,
      -0.695852277484,
      0.313756687878,
      -0.451544944347,
      0.7350424238,
      -0.456270956375,
      0.501527117496,
      0.164185068076,
      -0.205830722882,
      0.554622774767,
      0.806242699953,
      0.434192177546,
      0.0,
      0.0,
      0.0,
      1.0,
      -0.646033845869,
      -0.695857231915,
      0.313724373906,
      -0.451552914659,
      0.735030327725,
      -0.456290891553,
      0.501526708771,
      0.1641821826,
      -0.205841413026,
      0.554600157841,
      0.806255528729,
      0.434201985594,
      0.0,
      0.0,
      0.0,
      1.0},
     {1.0, 1.0, 0.5, 0.5, 1.0, 1.0, 0.5333333333333333, 0.4666666666666667},
     {{"overlap_2", 0.6934921697},
      {"overlap_3", 0.6509177455},
      {"quat_3", 0.7307613471},
      {"trans_3", 0.8065372594},
      {"total", 6.1936534315}}},
    {"divisor8_different",
     8,
     1,
     60,
     47,
     {0.04189871145409026, 0.044280734082114956},
     {-0.646041014946, -0.695836916189, 0.313754670205, -0.451549088558, 0.735029828267,
      -0.456287949499, 0.50153011744, 0.16418533502, -0.205820695182, 0.554628067456,
      0.806241619011, 0.434192690145, 0.0, 0.0, 0.0, 1.0},
     {1.0, 1.0, 0.5, 0.5, 1.0, 1.0, 0.6170212765957447, 0.3829787234042553},
     {{"overlap_2", 0.6931773561},
      {"overlap_3", 0.6209384264},
      {"quat_3", 0.712836007},
      {"trans_3", 0.8338142018},
      {"total", 6.2551822267}}},
};

/// The stand-in's pairs (omnet_standin.py case_pair): source FormulaCloud(batch, n, 0); N == M:
/// the target is the source moved by FormulaMotion and reversed in order; else
/// FormulaCloud(batch, m, 1) moved.
PairBatch ParityPair(const ParityCase& c) {
    const torch::Tensor motion = testing::FormulaMotion(c.batch).to(torch::kDouble);
    const torch::Tensor R = motion.index({Slice(), Slice(0, 3), Slice(0, 3)});
    const torch::Tensor t = motion.index({Slice(), Slice(0, 3), 3}).unsqueeze(1);
    PairBatch batch;
    batch.source = testing::FormulaCloud(c.batch, c.n, 0.0).to(torch::kDouble);
    const torch::Tensor target =
        c.n == c.m ? batch.source : testing::FormulaCloud(c.batch, c.m, 1.0).to(torch::kDouble);
    batch.target = torch::bmm(target, R.transpose(1, 2)) + t;
    if (c.n == c.m) batch.target = batch.target.flip(1);
    batch.T_gt = motion;
    return batch;
}

/// A float64 net of the case's width with the formula weights (and the case's overlap biases)
/// loaded by LoadOmnetStateDict; the narrow ones after a round trip through a torch.save zip,
/// read back by the reader the authors' checkpoints go through (430 MB at full width: slow).
std::unique_ptr<OmnetNet> FormulaNet(const ParityCase& c) {
    OmnetConfig config;
    config.width_divisor = c.divisor;
    OmnetNet filled(config);
    filled.to(torch::kDouble);
    testing::FormulaFill(filled);
    StateDict sd;
    for (const auto& p : filled.named_parameters()) sd.emplace_back(p.key(), p.value());
    for (const auto& b : filled.named_buffers()) sd.emplace_back(b.key(), b.value());
    {
        torch::NoGradGuard no_grad;
        for (auto& [key, value] : sd) {
            for (int i : {1, 2}) {
                if (key == "decoder." + std::to_string(i) + ".conv_block4.0.bias") {
                    value[1] += c.overlap_bias[static_cast<size_t>(i - 1)];
                }
            }
        }
    }
    if (c.divisor > 1) sd = ReadTorchSaveBytes(WriteTorchSaveZip(sd), "formula.pth").tensors;
    auto net = std::make_unique<OmnetNet>(config);
    net->to(torch::kDouble);
    LoadStrictStateDict(*net, sd, "formula.pth", "OMNet");
    net->eval();
    return net;
}

TEST_F(OmnetTest, ForwardAndLossMatchTheStandIn) {
    for (const ParityCase& c : kCases) {
        SCOPED_TRACE(c.name);
        auto net = FormulaNet(c);
        torch::NoGradGuard no_grad;
        const PairBatch batch = ParityPair(c);
        const NetOutput out = net->Forward(batch);
        const torch::Tensor T = out.T.contiguous().view({-1});
        ASSERT_EQ(T.numel(), static_cast<int64_t>(c.T.size()));
        for (int64_t i = 0; i < T.numel(); ++i) {
            EXPECT_NEAR(T[i].item<double>(), c.T[static_cast<size_t>(i)], 1e-9) << "T entry " << i;
        }
        for (int i = 0; i < 4; ++i) {
            const std::string n = std::to_string(i);
            EXPECT_DOUBLE_EQ(out.aux.at("mask_source_" + n).mean().item<double>(),
                             c.mask_fraction[static_cast<size_t>(i)])
                << n;
            EXPECT_DOUBLE_EQ(out.aux.at("mask_target_" + n).mean().item<double>(),
                             c.mask_fraction[static_cast<size_t>(4 + i)])
                << n;
        }
        const LossTerms terms = net->Loss(batch, out);
        for (const auto& [key, want] : c.loss) {
            EXPECT_NEAR(terms.at(key).item<double>(), want, 1e-8) << key;
        }
    }
}

TEST_F(OmnetTest, LossTrainsEveryIterationsRegressor) {
    // Training mode, float32 as `regbench train` runs it: the total is finite and reaches the
    // regressor of every iteration (each iteration has its own weights) and the mask decoder
    // of the first two. (From the third on a mask that holds no point zeroes every feature, as
    // in the authors' code, and with them the weights' gradients; the biases still learn.)
    torch::manual_seed(3);
    OmnetConfig config;
    config.width_divisor = 16;
    OmnetNet net(config);
    net.train();
    PairBatch batch;
    batch.source = testing::FormulaCloud(2, 50, 0.0);
    batch.target = testing::FormulaCloud(2, 43, 1.0);
    batch.T_gt = testing::FormulaMotion(2);
    const NetOutput out = net.Forward(batch);
    const torch::Tensor total = net.Loss(batch, out).at("total");
    ASSERT_TRUE(std::isfinite(total.item<double>()));
    total.backward();
    for (const auto& p : net.named_parameters()) {
        const std::string& key = p.key();
        const bool early_decoder =
            key == "decoder.0.conv_block4.0.weight" || key == "decoder.1.conv_block4.0.weight";
        if (key.find("final_fc.0.bias") == std::string::npos && !early_decoder) continue;
        ASSERT_TRUE(p.value().grad().defined()) << key;
        EXPECT_GT(p.value().grad().abs().sum().item<double>(), 0.0) << key;
    }
}

TEST_F(OmnetTest, StateDictOfAnotherShapeIsRefusedNamingTheKey) {
    OmnetConfig eighth;
    eighth.width_divisor = 8;
    OmnetNet small(eighth);
    StateDict sd;
    for (const auto& p : small.named_parameters()) sd.emplace_back(p.key(), p.value());
    for (const auto& b : small.named_buffers()) sd.emplace_back(b.key(), b.value());
    OmnetConfig quarter;
    quarter.width_divisor = 4;
    OmnetNet other(quarter);
    try {
        LoadStrictStateDict(other, sd, "eighth.pth", "OMNet");
        FAIL() << "a state dict of another width was accepted";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("eighth.pth: tensor encoder.0.conv_block1.0.weight"),
                  std::string::npos)
            << e.what();
    }
    sd.pop_back();
    OmnetNet same(eighth);
    EXPECT_THROW(LoadStrictStateDict(same, sd, "short.pth", "OMNet"), std::runtime_error);
}

// ---- the authors' checkpoint file ----------------------------------------------------------

TEST_F(OmnetTest, TheAuthorsCheckpointLayoutImportsAndRefusesOthersByName) {
    // Written at test time by Debian's python3-torch: `omnet_standin.py save FILE 8`, the
    // authors' checkpoint dict (state_dict under DataParallel's "module." prefix, Adam and
    // ExponentialLR state of a real step, step, epoch, scores) with the formula weights at
    // width / 8, which tests/networks/formula_fixture.hpp computes here independently.
    const char* env = std::getenv("REGBENCH_SOURCE_DIR");
    const std::string source = env != nullptr ? env : ".";
    const std::filesystem::path dir = regbench::testing::FreshTempDir("omnet_ckpt");
    const std::filesystem::path pth = dir / "model_best.pth";
    const auto [rc, out] = regbench::testing::RunShell(
        "/usr/bin/python3 " + source + "/networks/families/omnet/omnet_standin.py save " +
        pth.string() + " 8 2>&1");
    ASSERT_EQ(rc, 0) << out;
    ImportOptions options;
    options.from = "omnet";
    ImportAuthorsCheckpoint(pth.string(), (dir / "imported").string(), options);
    const auto imported = LoadNetFromCheckpoint((dir / "imported").string());
    EXPECT_EQ(imported->Config().at("width_divisor"), 8);
    OmnetConfig eighth;
    eighth.width_divisor = 8;
    OmnetNet formula(eighth);
    testing::FormulaFill(formula);
    formula.eval();
    std::map<std::string, torch::Tensor> theirs;
    for (const auto& p : imported->named_parameters()) theirs[p.key()] = p.value();
    for (const auto& b : imported->named_buffers()) theirs[b.key()] = b.value();
    for (const auto& p : formula.named_parameters()) {
        ASSERT_TRUE(theirs.count(p.key())) << p.key();
        EXPECT_TRUE(torch::allclose(theirs.at(p.key()), p.value(), 1e-6, 1e-7)) << p.key();
    }
    {
        torch::NoGradGuard no_grad;
        PairBatch pair;
        pair.source = testing::FormulaCloud(1, 50, 0.0);
        pair.target = testing::FormulaCloud(1, 41, 1.0);
        EXPECT_TRUE(
            torch::allclose(imported->Forward(pair).T, formula.Forward(pair).T, 1e-5, 1e-6));
    }
    std::filesystem::remove_all(dir);
}

TEST_F(OmnetTest, MacsAreTheLayersProductsCountedByHand) {
    // The authors' widths on 717 + 717 points, per iteration (x4), by hand:
    // encoder per point 3*64 + 64*64 + 64*64 + 64*128 + 128*1024 = 147,648;
    // fusion per point 64*1024 + 1024*1024 + 1024*512 = 1,638,400, per cloud 2*1024*1024;
    // decoder per point 512*512 + 512*256 + 256*256 + 256*2 = 459,264;
    // regression 3072*2048 + 2048*1024 + 1024*512 + 512*256 + 256*7 = 9,045,760.
    const auto macs = OmnetForwardMacs(OmnetConfig{}, 717, 717);
    EXPECT_EQ(macs.at("encoder"), 4LL * 1434 * 147648);
    EXPECT_EQ(macs.at("fusion"), 4LL * (1434LL * 1638400 + 2 * 2 * 1024 * 1024));
    EXPECT_EQ(macs.at("decoder"), 4LL * 1434 * 459264);
    EXPECT_EQ(macs.at("regression"), 4LL * 9045760);
    EXPECT_THROW(FindFamily("omnet").forward_cost(ToJson(OmnetConfig{}), 0, 717),
                 std::invalid_argument);
}

}  // namespace
}  // namespace regbench::networks
