#include "networks/cost.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace regbench::networks {
namespace {

nlohmann::json TinyOgmm() {
    return {{"arch", "ogmm"},
            {"emb_dims", 4},
            {"k", 2},
            {"spe_k", 2},
            {"anchors", 2},
            {"clusters", 2},
            {"spe", true},
            {"csa", true},
            {"osp", true},
            {"attention", "clustered"},
            {"gmm_iterations", 1}};
}

TEST(ForwardCost, OgmmMatchesAHandCountForATinyConfig) {
    // Hand count, d = 4, k = 2, spe_k = 2, A = 2 anchors, J = 2, one GMM round, N = M = 3.
    // Per cloud:
    //   DGCNN   3 * 2 * 45,440 (edge convs 6*64 + 64*64 + 64*128 + 128*256 = 45,440)
    //           + 3 * 512 * 4 + 3 * 3^2 (kNN Gram)                          = 278,811
    //   SPE     3 * (64 + 64 * 2 + 64 * 4) + 27                             =   1,371
    //   3 attention blocks (2 self, 1 cross), each 3 queries onto 2 keys:
    //           8 * 16 * 3 + 2 * 16 * 2 + 2 * 3 * 2 * 4 = 384 + 64 + 48 = 496 -> 1,488
    //   FPS     3 calls * 3 * 3 points * 2 anchors                          =      54
    //   CONV3_a 8 * 16 * 3                                                  =     384
    //   overlap per point: proj 4*2 + 2, CONV3_b 6*8 + 64 + 32, CONV3_o 4*2 + 2*2 + 2
    //           = 10 + 144 + 14 = 168, times 3                              =     504
    //   GMM fit 3 * 3 * 2 * (1 + 2 * 1)                                     =      54
    //   cluster features 3 * 2 * 4                                          =      24
    //   per cloud                                                           = 282,690
    // Pair: overlap cosines 3 * 3 * 4 + pooled logits 2 * 9 = 54; matching 2 * 2 * 4 +
    // 2 * 2 * 3 + 9 * 2 = 46. Total 2 * 282,690 + 54 + 46 = 565,480.
    const ForwardCost cost = ComputeForwardCost(TinyOgmm(), 3, 3);
    EXPECT_EQ(cost.total, 565480);
    EXPECT_EQ(cost.parts.at("dgcnn"), 2 * 278811);
    EXPECT_EQ(cost.parts.at("attention"), 2 * 1488);
    EXPECT_EQ(cost.parts.at("overlap"), 2 * 504 + 54);
    EXPECT_EQ(cost.parts.at("matching"), 46);
    // Full attention: 3 keys per block, 8 * 16 * 3 + 2 * 16 * 3 + 2 * 3 * 3 * 4 = 552, no FPS:
    // per cloud 282,690 - 1,488 + 3 * 552 - 54 = 282,804; total 565,708.
    nlohmann::json full = TinyOgmm();
    full["attention"] = "full";
    EXPECT_EQ(ComputeForwardCost(full, 3, 3).total, 565708);
    // Without SPE, CSA and OSP: per cloud DGCNN + cross-attention 496 + FPS 1 * 18 + CONV3_a
    // 384 + GMM 54 + cluster features 24 = 279,787; total 2 * 279,787 + 46 = 559,620.
    nlohmann::json bare = TinyOgmm();
    bare["spe"] = false;
    bare["csa"] = false;
    bare["osp"] = false;
    EXPECT_EQ(ComputeForwardCost(bare, 3, 3).total, 559620);
}

TEST(ForwardCost, DeepGmrMatchesAHandCountForTinyConfigs) {
    // Paper variant, d = 8, k = 2, CONV3 hidden 4, J = 2, N = M = 5, per cloud:
    //   DGCNN 5 * 2 * 45,440 + 5 * 512 * 8 + 3 * 25 = 454,400 + 20,480 + 75 = 474,955
    //   head  5 * (8 * 4 + 4 * 4 + 4 * 2) = 280; mixture 7 * 5 * 2 = 70
    // Total 2 * 475,305 + two registrations 2 * 9 * 2 = 950,646.
    const nlohmann::json paper = {{"arch", "deepgmr"}, {"features", "dgcnn"}, {"clusters", 2},
                                  {"emb_dims", 8},     {"dgcnn_k", 2},        {"head_hidden", 4},
                                  {"rri_k", 20}};
    EXPECT_EQ(ComputeForwardCost(paper, 5, 5).total, 950646);
    // Original on xyz, J = 16, N = 10, M = 6: per point encoder 3*64 + 64*128 + 128*256 +
    // 256*1024 = 303,296, decoder 2048*512 + 512*256 + 256*128 + 128*16 = 1,214,464, mixture
    // 7 * 16 = 112: 1,517,872 per point; 16 points -> 24,285,952, plus 2 * 9 * 16 = 288.
    nlohmann::json xyz = paper;
    xyz["features"] = "xyz";
    xyz["clusters"] = 16;
    EXPECT_EQ(ComputeForwardCost(xyz, 10, 6).total, 24286240);
    // RRI with k = 20: the first conv sees 80 channels, (80 - 3) * 64 more MACs per point.
    nlohmann::json rri = xyz;
    rri["features"] = "rri";
    EXPECT_EQ(ComputeForwardCost(rri, 10, 6).total, 24286240 + 16 * 77 * 64);
}

TEST(ForwardCost, RefusesMissingKeysAndEmptyClouds) {
    nlohmann::json c = TinyOgmm();
    c.erase("emb_dims");
    EXPECT_THROW(ComputeForwardCost(c, 3, 3), std::invalid_argument);
    EXPECT_THROW(ComputeForwardCost(TinyOgmm(), 0, 3), std::invalid_argument);
    EXPECT_THROW(ComputeForwardCost({{"arch", "pointnetlk"}}, 3, 3), std::invalid_argument);
}

}  // namespace
}  // namespace regbench::networks
