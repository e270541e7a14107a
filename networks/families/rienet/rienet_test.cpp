#include "networks/families/rienet/net.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "networks/cost.hpp"
#include "networks/family.hpp"
#include "networks/layers/layers.hpp"
#include "tests/networks/formula_fixture.hpp"
#include "tests/networks/one_thread_test.hpp"
#include "tests/networks/state_fixture.hpp"

namespace regbench::networks {
namespace {

using torch::indexing::Slice;

class RienetTest : public OneThreadTest {};

// ---- the authors' layout --------------------------------------------------------------------

TEST_F(RienetTest, ParameterCountsMatchTheAuthorsCheckpoints) {
    // Counted with torch from the authors' released checkpoints (supersyq/RIENet, pretrained/
    // */model.best.t7, the non-running float tensors of `model`): 275,185 for modelnet and
    // 7scenes (dim 8), 276,993 for modelnet-unseen and icl_nuim (dim 16).
    EXPECT_EQ(CountParameters(RienetNet(RienetConfig{})), 275185);
    RienetConfig wide;
    wide.dim = 16;
    EXPECT_EQ(CountParameters(RienetNet(wide)), 276993);
    // The modules the authors build and never call, by hand: PointNet convs 3*32 + 32*32 +
    // 32*64 + 64*128 + 128*256 = 44,128 and BN 2 * 512 = 1,024; Pointer convs 512*256 + 256*64 +
    // 64*32 = 149,504 and BN 2 * 352 = 704: 195,360.
    int64_t unused = 0;
    for (const auto& p : RienetNet(RienetConfig{}).named_parameters()) {
        if (p.key().rfind("single_point_embed.", 0) == 0 ||
            p.key().rfind("forwards.fuse.", 0) == 0) {
            unused += p.value().numel();
        }
    }
    EXPECT_EQ(unused, 195360);
}

TEST_F(RienetTest, StateDictHasTheAuthorsKeysAndShapes) {
    RienetNet net(RienetConfig{});
    const std::map<std::string, std::vector<int64_t>> shapes = StateShapes(net);
    // The authors' modelnet checkpoint holds 129 tensors; a sample of their keys and shapes.
    EXPECT_EQ(shapes.size(), 129u);
    const std::map<std::string, std::vector<int64_t>> theirs = {
        {"emb_nn.model.conv1.weight", {32, 3, 1, 1}},
        {"emb_nn.model.conv5.weight", {256, 256, 1, 1}},
        {"emb_nn.model.bn5.running_var", {256}},
        {"single_point_embed.conv5.weight", {256, 128, 1}},
        {"forwards.weight_function.model1.0.weight", {8, 3, 3, 1}},
        {"forwards.weight_function.model1.4.num_batches_tracked", {}},
        {"forwards.weight_function.model3.3.bias", {16}},
        {"forwards.weight_function.model4.3.weight", {1, 8, 1}},
        {"forwards.fuse.conv1.weight", {256, 512, 1}},
        {"forwards.fuse.bn3.running_mean", {32}},
    };
    ExpectShapesInclude(shapes, theirs);
}

// ---- parity with the PyTorch stand-in -------------------------------------------------------

struct ParityCase {
    const char* name;
    int64_t batch, n, m;
    std::vector<double> T;  // [batch, 4, 4] row-major
    double global_alignment, consensus, spatial_consistency;
};

// From `/usr/bin/python3 networks/families/rienet/rienet_standin.py expected` (PyTorch 1.13,
// float64): the stand-in's forward with the formula weights. On shared_points the authors' own
// RIENET (model.py made CPU-only, float32; `rienet_standin.py authors DIR`) gives R within 1.4e-5
// and t within 6e-8 of the stand-in's float32 run, which is within 4.2e-5 of these float64 values.
// The authors' code cannot run different_sizes (N != M).
const ParityCase kSharedPoints = {"shared_points",
                                  2,
                                  300,
                                  300,
                                  {0.966771491587,
                                   -0.161109293568,
                                   0.198485965702,
                                   0.0996889115965,
                                   0.190975741388,
                                   0.971299165667,
                                   -0.141796322148,
                                   -0.199694320533,
                                   -0.169944547591,
                                   0.17499064632,
                                   0.969792309953,
                                   -0.00063951050894,
                                   0.0,
                                   0.0,
                                   0.0,
                                   1.0,
                                   0.87671055544,
                                   -0.225157426395,
                                   0.425067918478,
                                   0.101230056088,
                                   0.340393684369,
                                   0.914778981985,
                                   -0.217512192212,
                                   -0.199381549222,
                                   -0.339868712332,
                                   0.335385669727,
                                   0.878638555334,
                                   0.0491915644446,
                                   0.0,
                                   0.0,
                                   0.0,
                                   1.0},
                                  0.0322818477761,
                                  597.236929412,
                                  16.5412821395};
const ParityCase kDifferentSizes = {
    "different_sizes",
    1,
    300,
    257,
    {0.778974989499, -0.0184508986522, -0.62678347942, 0.103897946858, 0.60637003492,
     0.276783509932, 0.745457087552, -0.203806659784, 0.159728978229, -0.960755147251,
     0.226795503803, 0.00450225969405, 0.0, 0.0, 0.0, 1.0},
    0.244340464084,
    296.864296245,
    16.1472958191};

/// The stand-in's pairs: source FormulaCloud(batch, n, 0); shared_points: the target is the
/// source moved by FormulaMotion and reversed in order; different_sizes: FormulaCloud(1, m, 1)
/// moved by FormulaMotion's first motion.
PairBatch ParityPair(const ParityCase& c, torch::Dtype dtype) {
    const torch::Tensor motion = testing::FormulaMotion(c.batch).to(torch::kDouble);
    const torch::Tensor R = motion.index({Slice(), Slice(0, 3), Slice(0, 3)});
    const torch::Tensor t = motion.index({Slice(), Slice(0, 3), 3}).unsqueeze(1);
    PairBatch batch;
    batch.source = testing::FormulaCloud(c.batch, c.n, 0.0).to(torch::kDouble);
    if (c.n == c.m) {
        batch.target = (torch::bmm(batch.source, R.transpose(1, 2)) + t).flip(1);
    } else {
        batch.target = torch::bmm(testing::FormulaCloud(c.batch, c.m, 1.0).to(torch::kDouble),
                                  R.transpose(1, 2)) +
                       t;
    }
    batch.source = batch.source.to(dtype);
    batch.target = batch.target.to(dtype);
    return batch;
}

/// `autograd` runs the forward with gradients on: the LibTorch composition of the refined
/// matching map instead of the fused inference kernel (networks/families/rienet/matching.hpp).
void ExpectParity(RienetNet& net, const ParityCase& c, torch::Dtype dtype, double tol,
                  bool autograd = false) {
    SCOPED_TRACE(c.name);
    net.eval();
    torch::AutoGradMode grad_mode(autograd);
    const PairBatch batch = ParityPair(c, dtype);
    const NetOutput out = net.Forward(batch);
    const torch::Tensor T = out.T.to(torch::kDouble).contiguous().view({-1});
    ASSERT_EQ(T.numel(), static_cast<int64_t>(c.T.size()));
    for (int64_t i = 0; i < T.numel(); ++i) {
        EXPECT_NEAR(T[i].item<double>(), c.T[static_cast<size_t>(i)], tol) << "T entry " << i;
    }
    const LossTerms terms = net.Loss(batch, out);
    const auto near = [&](const char* key, double want) {
        EXPECT_NEAR(terms.at(key).item<double>(), want, 10 * tol * std::max(1.0, want)) << key;
    };
    near("global_alignment", c.global_alignment);
    near("consensus", c.consensus);
    near("spatial_consistency", c.spatial_consistency);
}

/// A float64 net holding the formula weights after a round trip through a torch.save zip
/// (WriteTorchSaveZip, read back by the reader the authors' checkpoints go through).
std::unique_ptr<RienetNet> FormulaNetThroughTorchSave() {
    RienetNet filled(RienetConfig{});
    filled.to(torch::kDouble);
    testing::FormulaFill(filled);
    StateDict sd;
    for (const auto& p : filled.named_parameters()) sd.emplace_back(p.key(), p.value());
    for (const auto& b : filled.named_buffers()) sd.emplace_back(b.key(), b.value());
    const TorchSaveContents read = ReadTorchSaveBytes(WriteTorchSaveZip(sd), "formula.pth");
    auto net = std::make_unique<RienetNet>(RienetConfig{});
    net->to(torch::kDouble);
    LoadStrictStateDict(*net, read.tensors, "formula.pth", "RIENet");
    return net;
}

TEST_F(RienetTest, ForwardMatchesTheStandInOnSharedPoints) {
    auto net = FormulaNetThroughTorchSave();
    ExpectParity(*net, kSharedPoints, torch::kDouble, 1e-4);
}

TEST_F(RienetTest, ForwardWithAutogradMatchesTheStandInAsWithout) {
    auto net = FormulaNetThroughTorchSave();
    ExpectParity(*net, kSharedPoints, torch::kDouble, 1e-4, /*autograd=*/true);
    ExpectParity(*net, kDifferentSizes, torch::kDouble, 1e-4, /*autograd=*/true);
}

TEST_F(RienetTest, ForwardRunsOnCloudsOfDifferentSizesAsTheStandIn) {
    auto net = FormulaNetThroughTorchSave();
    ExpectParity(*net, kDifferentSizes, torch::kDouble, 1e-4);
}

TEST_F(RienetTest, Float32ForwardIsWithinFloatRoundingOfTheStandIn) {
    // The stand-in's own float32 run is 4.2e-5 (shared) and 9.7e-5 (different sizes) from its
    // float64 one: these pairs amplify rounding, so float32 is held to 5e-4.
    RienetNet net(RienetConfig{});
    testing::FormulaFill(net);
    ExpectParity(net, kSharedPoints, torch::kFloat, 5e-4);
}

// ---- checkpoints, configs and inputs ----------------------------------------------------------

TEST_F(RienetTest, LoadingRefusesMissingExtraAndMisshapedTensorsByName) {
    RienetNet net(RienetConfig{});
    StateDict sd;
    for (const auto& p : net.named_parameters()) sd.emplace_back(p.key(), p.value().clone());
    for (const auto& b : net.named_buffers()) sd.emplace_back(b.key(), b.value().clone());
    const auto message = [&net](const StateDict& tensors) {
        try {
            LoadStrictStateDict(net, tensors, "x.t7", "RIENet");
        } catch (const std::runtime_error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    StateDict missing(sd.begin() + 1, sd.end());
    EXPECT_EQ(message(missing), "x.t7: has no tensor " + sd.front().first + " (RIENet state dict)");
    StateDict extra = sd;
    extra.emplace_back("module.head.weight", torch::zeros({1}));
    EXPECT_EQ(message(extra), "x.t7: tensor module.head.weight is not in RIENet's state dict");
    StateDict wrong = sd;
    for (auto& [key, value] : wrong) {
        if (key == "forwards.weight_function.model1.0.weight") value = torch::zeros({16, 3, 3, 1});
    }
    EXPECT_NE(message(wrong).find("tensor forwards.weight_function.model1.0.weight has shape "
                                  "[16, 3, 3, 1], RIENet's is [8, 3, 3, 1]"),
              std::string::npos)
        << message(wrong);
    EXPECT_EQ(message(sd), "no error");
}

TEST_F(RienetTest, ConfigRoundTripsAndBadValuesAreRefusedByName) {
    RienetConfig c;
    c.dim = 16;
    c.k = 8;
    const nlohmann::json j = ToJson(c);
    EXPECT_EQ(j.at("arch"), "rienet");
    EXPECT_EQ(ToJson(RienetConfigFromJson(j)), j);
    EXPECT_EQ(RienetNet(c).Config(), j);
    EXPECT_THROW(RienetConfigFromJson({{"k", 1}}), std::invalid_argument);
    EXPECT_THROW(RienetConfigFromJson({{"loss_margin", 0.0}}), std::invalid_argument);
}

TEST_F(RienetTest, TooFewPointsOrBadShapesAreRefusedWithAClearError) {
    RienetNet net(RienetConfig{});
    net.eval();
    torch::NoGradGuard no_grad;
    PairBatch batch;
    batch.source = testing::FormulaCloud(1, 4, 0.0);
    batch.target = testing::FormulaCloud(1, 50, 1.0);
    try {
        net.Forward(batch);
        ADD_FAILURE() << "4 points accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_EQ(std::string(e.what()),
                  "rienet: source has 4 points, needs at least 5 (k and k_nc neighbours)");
    }
    batch.source = testing::FormulaCloud(2, 50, 0.0);
    EXPECT_THROW(net.Forward(batch), std::invalid_argument);  // batch sizes differ
}

// ---- training -------------------------------------------------------------------------------

TEST_F(RienetTest, UnsupervisedLossTrainsTheUsedModulesOnly) {
    RienetConfig c;
    c.emb_dims = 32;
    c.keypoints = 64;  // more than the 40 points: clamped to N
    RienetNet net(c);
    net.train();
    PairBatch batch = ParityPair({"small", 2, 40, 40, {}, 0, 0, 0}, torch::kFloat);
    const NetOutput out = net.Forward(batch);
    const LossTerms terms = net.Loss(batch, out);  // no T_gt: unsupervised
    ASSERT_TRUE(std::isfinite(terms.at("total").item<double>()));
    EXPECT_NEAR(terms.at("total").item<double>(),
                terms.at("global_alignment").item<double>() + terms.at("consensus").item<double>() +
                    terms.at("spatial_consistency").item<double>(),
                1e-4 * terms.at("total").item<double>());
    terms.at("total").backward();
    for (const auto& p : net.named_parameters()) {
        const bool used =
            p.key().rfind("emb_nn.", 0) == 0 || p.key().rfind("forwards.weight_function.", 0) == 0;
        const bool has_grad =
            p.value().grad().defined() && p.value().grad().abs().sum().item<double>() > 0;
        EXPECT_EQ(has_grad, used) << p.key();
    }
}

// ---- cost -------------------------------------------------------------------------------------

TEST_F(RienetTest, MacCountFollowsTheLayerWidths) {
    const auto parts = RienetForwardMacs(RienetConfig{}, 717, 717);
    // By hand: per point 5 edges x (3*32 + 32*32 + 32*64 + 64*128 = 11,360) + 256*256 = 122,336;
    // the source in each of 3 iterations and the target once.
    EXPECT_EQ(parts.at("dgcnn"), 4LL * 717 * 122336);
    // Feature Gram 717 * 717 * 256 and pseudo targets 717 * 717 * 3, three times.
    EXPECT_EQ(parts.at("matching"), 3LL * 717 * 717 * 259);
    int64_t sum = 0;
    for (const auto& [part, macs] : parts) {
        if (part != "total") sum += macs;
    }
    EXPECT_EQ(parts.at("total"), sum);
    EXPECT_THROW(FindFamily("rienet").forward_cost(ToJson(RienetConfig{}), 0, 717),
                 std::invalid_argument);
}

}  // namespace
}  // namespace regbench::networks
