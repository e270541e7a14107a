#pragma once
// RIENet (Shen et al., "Reliable Inlier Evaluation for Unsupervised Point Cloud Registration",
// AAAI 2022), as the authors implement it (supersyq/RIENet, model.py and utils.py): three
// iterations with shared weights, each a light DGCNN (relative coordinates of k neighbours,
// 3 -> 32 -> 32 -> 64 -> 128, the four max-pooled maps concatenated, 256 -> emb_dims), a
// matching map softmax(-d) of feature distances refined by neighbourhood consensus, pseudo
// correspondences, an inlier discriminator on the two neighbourhoods and a weighted SVD. Trained
// without labels: Huber chamfer, neighbourhood consensus and spatial consistency losses.
//
// Module and parameter names are the keys of the authors' RIENET state dict, one to one
// (including the two modules they build and never call, `single_point_embed` and
// `forwards.fuse`, which hold 195,360 of the 275,185 parameters at dim 8).
// Deviations from the authors' code (docs in the report of issue 42):
//  - clouds of different sizes: the neighbourhood consensus sums the matching scores over the
//    k_nc - 1 non-self neighbours of the source point and of the target point; their code
//    reshapes with the source's size and fails unless N == M (the same numbers when N == M);
//  - kNN by exact distances (nanoflann); theirs ranks float32 Gram-matrix distances, so
//    near-ties below float32 resolution can order differently;
//  - the losses' keypoints are min(keypoints, N) (theirs fails when N < keypoints);
//  - in eval mode the target's features are computed once, not once per iteration (the target
//    does not move; in training mode they are recomputed, as BatchNorm's running statistics
//    count every call).
#include <torch/torch.h>

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/params.hpp"
#include "networks/checkpoint/torch_save_reader.hpp"
#include "networks/net.hpp"

namespace regbench::networks {

/// The authors' hyper-parameters (config/train.yaml, ModelNet40), their names in comments; the
/// ranges (Validate) are in networks/families/rienet/net.cpp.
struct RienetConfig {
    std::string name = "rienet";  ///< zoo name it came from
    int emb_dims = 256;           ///< light DGCNN feature width (emb_dims)
    int dim = 8;                  ///< inlier discriminator width (dim: 8; 16 unseen, ICL-NUIM)
    int iterations = 3;           ///< n_iters, weights shared
    int k = 5;                    ///< DGCNN and inlier neighbourhood size, self included (list_k1)
    int k_nc = 5;                 ///< neighbourhood consensus size, self included (list_k2)
    double nn_margin = 0.7;       ///< consensus margin: distances scaled by exp(margin - nc)
    double loss_margin = 0.01;    ///< Huber threshold of the chamfer loss (loss_margin)
    int keypoints = 256;          ///< points with the highest inlier weight in the losses

    template <class F>
    void Fields(F&& f) {
        f("name", name, "zoo name it came from");
        f("emb_dims", emb_dims, "light DGCNN feature width (the authors' emb_dims)");
        f("dim", dim, "inlier discriminator width (the authors' dim: 8 ModelNet40, 16 ICL-NUIM)");
        f("iterations", iterations, "registration iterations with shared weights (n_iters)");
        f("k", k, "DGCNN and inlier neighbourhood size, the point itself included (list_k1)");
        f("k_nc", k_nc, "neighbourhood consensus size, the point itself included (list_k2)");
        f("nn_margin", nn_margin,
          "consensus margin: feature distances scaled by exp(margin - consensus)");
        f("loss_margin", loss_margin,
          "Huber threshold of the chamfer loss, in cloud units (loss_margin)");
        f("keypoints", keypoints,
          "points with the highest inlier weight in the losses (at most N)");
    }
    void Validate(ParamCheck& c) const;
};

/// {"arch": "rienet", "name", "emb_dims", ...}; every field always present.
nlohmann::json ToJson(const RienetConfig& c);
/// Reads the keys of `j` over the defaults (ParseNetConfig); unknown keys or bad values throw
/// std::invalid_argument naming them.
RienetConfig RienetConfigFromJson(const nlohmann::json& j);

/// The authors' DGCNN: bias-free Conv2d 3->32->32->64->128 on the neighbours' relative
/// coordinates (BN2d, ReLU), each max-pooled over k, concatenated (256), Conv2d 256->emb (BN2d,
/// ReLU). Children conv1..conv5 then bn1..bn5.
class RienetDgcnnImpl : public torch::nn::Module {
public:
    explicit RienetDgcnnImpl(int64_t emb_dims);
    /// Rows xyz [B, N, 3], neighbours idx [B, N, k] (self first) -> features [B, N, emb].
    torch::Tensor forward(const torch::Tensor& xyz, const torch::Tensor& idx);

private:
    std::vector<torch::nn::Conv2d> convs_;
    std::vector<torch::nn::BatchNorm2d> bns_;
};
TORCH_MODULE(RienetDgcnn);

/// The authors' Discriminator: model1 (two Conv2d with a (3, 1) kernel along the neighbours,
/// BN2d, LeakyReLU 0.2: 3 -> dim -> 2 dim) on both neighbourhoods, their difference through
/// model2 (features) and model3 (softmax weights over the k neighbours), both 2 dim -> 16 -> 16,
/// pooled, then model4 (Conv1d 16 -> 8, BN, LeakyReLU, 8 -> 1) and 1 - tanh|.|.
class InlierDiscriminatorImpl : public torch::nn::Module {
public:
    explicit InlierDiscriminatorImpl(int64_t dim);
    /// Neighbourhood offsets (centre minus neighbour) of the pseudo targets and of the source
    /// [B, N, k, 3] -> inlier confidence [B, N] in (0, 1].
    torch::Tensor forward(const torch::Tensor& pseudo, const torch::Tensor& source);

private:
    torch::nn::Sequential model1_{nullptr}, model2_{nullptr}, model3_{nullptr}, model4_{nullptr};
};
TORCH_MODULE(InlierDiscriminator);

class RienetNet : public RegistrationNet {
public:
    explicit RienetNet(const RienetConfig& config);
    /// T, and in aux what the loss needs per iteration i (moved_i, corr_i, pseudo_local_i,
    /// weight_i, neighbours_i, matching_i). The authors' forward also computes the loss terms;
    /// here Loss does, so inference skips them. Throws std::invalid_argument on clouds of other
    /// shapes or with fewer points than k or k_nc.
    NetOutput Forward(const PairBatch& batch) override;
    /// "global_alignment" (Huber chamfer), "consensus" (neighbourhood consensus),
    /// "spatial_consistency" (each summed over the iterations, as the authors' forward returns
    /// them) and "total", their sum (the authors' training loss); needs no ground truth.
    LossTerms Loss(const PairBatch& batch, const NetOutput& output) override;
    nlohmann::json Config() const override { return ToJson(config_); }

private:
    RienetConfig config_;
    RienetDgcnn dgcnn_{nullptr};                  // emb_nn.model
    InlierDiscriminator discriminator_{nullptr};  // forwards.weight_function
};

/// Multiply-accumulates of one batch-1 forward on N source and M target points, by part
/// (config: a RienetConfig in JSON). Counted like networks/cost.hpp: every convolution and matrix
/// product; element-wise work, softmax, the consensus sums and kd-tree searches are not.
/// "dgcnn" (the source every iteration, the target once: eval mode), "matching" (feature
/// distances and the pseudo correspondences), "discriminator", "svd" (the weighted covariance).
/// The loss terms are not part of a forward (RienetNet::Loss computes them).
std::map<std::string, int64_t> RienetForwardMacs(const RienetConfig& c, int64_t n, int64_t m);

}  // namespace regbench::networks
