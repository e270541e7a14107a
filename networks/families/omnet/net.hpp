#pragma once
// OMNet (Xu et al., "OMNet: Learning Overlapping Mask for Partial-to-Partial Point Cloud
// Registration", ICCV 2021) as the authors' PyTorch port implements it (hxwork/OMNet_Pytorch,
// model/module.py and model/net.py; the MegEngine original, megvii-research/OMNet, has the same
// blocks). Four iterations, each with its own weights: a PointNet encoder of both clouds (1x1
// convolutions 3 -> 64 -> 64 -> 64 -> 128 -> 1024, masked max-pooled to a global feature), a
// fusion of each point's 64-wide feature with both global features (2112 -> 1024 -> 1024 ->
// 512), a mask decoder (512 -> 512 -> 256 -> 256 -> 2 overlap logits) and a pose regressor on the
// max-pooled concatenation of both clouds' fused and decoded features (3072 -> 2048 -> 1024 ->
// 512 -> 256 -> 7: a unit quaternion and a translation). The source moves by each iteration's
// pose and the poses compose; from the third iteration on (the "mask delay" of two), each
// cloud's features are masked by the argmax of the previous iteration's overlap logits.
// Supervised: weighted cross-entropy of the overlap logits, L1 of the quaternion, squared
// error of the translation, every iteration.
//
// Module and parameter names are the keys of the authors' state dict (less DataParallel's
// "module." prefix), one to one: encoder.I.conv_blockJ.{0,1}, fusion.I..., decoder.I...,
// regression.I.fc_blockJ.{0,1} and final_fc.0.
// Deviations from the authors' code (docs/learned-methods.md, "OMNet"):
//  - clouds of different sizes: the regressor's input is each cloud's features max-pooled over
//    its own points, then concatenated; theirs concatenates the two clouds' per-point features
//    along the channels first, which fails unless N == M (the same numbers when N == M);
//  - the fusion's first convolution is split into its per-point part (the 64-wide feature) and
//    its per-cloud part (the two global features, the same for every point), computed once per
//    cloud: the same sums in another order, 1.9x fewer multiply-accumulates;
//  - `width_divisor` > 1 divides every hidden width (a CPU-trainable size; 1 is theirs).
#include <torch/torch.h>

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/params.hpp"
#include "networks/checkpoint/torch_save_reader.hpp"
#include "networks/net.hpp"

namespace regbench::networks {

/// The authors' hyper-parameters (experiments/experiment_omnet/params.json), names in comments;
/// the ranges (Validate) are in networks/families/omnet/net.cpp.
struct OmnetConfig {
    std::string name = "omnet";  ///< zoo name it came from
    int iterations = 4;          ///< titer; each iteration has its own weights
    int width_divisor = 1;       ///< every hidden width / this (1: the authors' widths)
    int mask_delay = 2;          ///< iterations that use no mask (theirs: 2)
    double overlap_dist = 0.1;   ///< training labels: overlapping when nearer (overlap_dist)
    double quat_weight = 1.0;    ///< L1 quaternion loss weight (loss_alpha1)
    double trans_weight = 4.0;   ///< squared translation loss weight (loss_alpha2)

    template <class F>
    void Fields(F&& f) {
        f("name", name, "zoo name it came from");
        f("iterations", iterations,
          "refinement iterations, each with its own weights (the authors' titer)");
        f("width_divisor", width_divisor,
          "every hidden width / this (1: the authors' 53.7 M parameters; 4: 3.4 M); divides 64");
        f("mask_delay", mask_delay, "first iterations that use no overlap mask (the authors': 2)");
        f("overlap_dist", overlap_dist,
          "training labels: a point overlaps when nearer than this to the other cloud under the "
          "true motion [unit-sphere units]");
        f("quat_weight", quat_weight,
          "weight of the L1 quaternion loss (the authors' loss_alpha1)");
        f("trans_weight", trans_weight,
          "weight of the squared translation loss (the authors' loss_alpha2)");
    }
    void Validate(ParamCheck& c) const;
};

/// {"arch": "omnet", "name", "iterations", ...}; every field always present.
nlohmann::json ToJson(const OmnetConfig& c);
/// Reads the keys of `j` over the defaults (ParseNetConfig); unknown keys or bad values throw
/// std::invalid_argument naming them.
OmnetConfig OmnetConfigFromJson(const nlohmann::json& j);

/// The hidden widths of a config: the authors' 64, 128, 256, 512, 1024, 2048 / width_divisor.
struct OmnetWidths {
    int64_t w64, w128, w256, w512, w1024, w2048;
    explicit OmnetWidths(int divisor);
};

/// One iteration's encoder: conv_block1..5 (Conv1d with bias, BN1d, ReLU), 3 -> 64 -> 64 -> 64
/// -> 128 -> 1024.
class OmnetEncoderImpl : public torch::nn::Module {
public:
    explicit OmnetEncoderImpl(const OmnetWidths& w);
    /// Points [B, 3, N], mask [B, 1, N] -> the masked 64-wide features [B, 64, N] and the
    /// global feature [B, 1024, 1] (max over the masked 1024-wide features).
    std::pair<torch::Tensor, torch::Tensor> forward(const torch::Tensor& x,
                                                    const torch::Tensor& mask);

private:
    std::vector<torch::nn::Sequential> blocks_;
};
TORCH_MODULE(OmnetEncoder);

/// One iteration's fusion: conv_block1..3, (64 + 2 x 1024) -> 1024 -> 1024 -> 512.
class OmnetFusionImpl : public torch::nn::Module {
public:
    explicit OmnetFusionImpl(const OmnetWidths& w);
    /// Masked 64-wide features [B, 64, N], the cloud's own and the other cloud's global
    /// features [B, 1024, 1], mask [B, 1, N] -> fused features [B, 512, N], masked.
    torch::Tensor forward(const torch::Tensor& local, const torch::Tensor& own_global,
                          const torch::Tensor& other_global, const torch::Tensor& mask);

private:
    int64_t local_width_;
    std::vector<torch::nn::Sequential> blocks_;
};
TORCH_MODULE(OmnetFusion);

/// One iteration's mask decoder: conv_block1..3 (512 -> 512 -> 256 -> 256, BN, ReLU) and
/// conv_block4 (256 -> 2 logits: not overlapping, overlapping).
class OmnetDecoderImpl : public torch::nn::Module {
public:
    explicit OmnetDecoderImpl(const OmnetWidths& w);
    /// Fused features [B, 512, N] -> the three hidden maps concatenated [B, 1024, N] and the
    /// logits [B, 2, N].
    std::pair<torch::Tensor, torch::Tensor> forward(const torch::Tensor& fused);

private:
    std::vector<torch::nn::Sequential> blocks_;
};
TORCH_MODULE(OmnetDecoder);

/// One iteration's pose regressor: fc_block1..4 (Linear, BN1d, ReLU), 3072 -> 2048 -> 1024 ->
/// 512 -> 256, and final_fc (256 -> 7).
class OmnetRegressionImpl : public torch::nn::Module {
public:
    explicit OmnetRegressionImpl(const OmnetWidths& w);
    /// [B, 3072] -> pose [B, 7]: a unit quaternion (w, x, y, z), then a translation.
    torch::Tensor forward(const torch::Tensor& x);

private:
    std::vector<torch::nn::Sequential> blocks_;
};
TORCH_MODULE(OmnetRegression);

class OmnetNet : public RegistrationNet {
public:
    explicit OmnetNet(const OmnetConfig& config);
    /// aux: "logits_source_I", "logits_target_I" [B, 2, N] and "mask_source_I",
    /// "mask_target_I" (the 0/1 masks iteration I used) and "pose_I" [B, 7] (the composed pose
    /// after iteration I), for I = 0 .. iterations - 1. Throws std::invalid_argument on clouds
    /// of other shapes.
    NetOutput Forward(const PairBatch& batch) override;
    /// Per iteration I, as the authors' loss: "overlap_I" (the mean of both clouds' weighted
    /// cross-entropy, weights 0.7 / 0.3 for not / overlapping; a point overlaps when its mask
    /// holds it and, moved by T_gt, it is nearer than overlap_dist to a point the other
    /// cloud's mask holds), "quat_I" (L1 to the ground truth's quaternion with w >= 0, times
    /// quat_weight) and "trans_I" (mean squared translation error, times trans_weight);
    /// "total" their sum.
    LossTerms Loss(const PairBatch& batch, const NetOutput& output) override;
    nlohmann::json Config() const override { return ToJson(config_); }

private:
    OmnetConfig config_;
    torch::nn::ModuleList encoder_, fusion_, decoder_, regression_;
};

/// Quaternion (w, x, y, z) [B, 4] -> rotation matrices [B, 3, 3] (Besl and McKay's formula, the
/// authors' torch_quat2mat; a rotation for unit quaternions).
torch::Tensor QuaternionToMatrix(const torch::Tensor& q);
/// The pose "first `first`, then `then`" [B, 7] (quaternion Hamilton product then * first,
/// translation R_then t_first + t_then): the authors' torch_transform_pose(first, then).
torch::Tensor ComposePoses(const torch::Tensor& first, const torch::Tensor& then);

/// Multiply-accumulates of one batch-1 forward on N source and M target points, by part
/// counted like networks/cost.hpp: every convolution and linear
/// layer; element-wise work and max-pooling are not. "encoder", "fusion" (the per-point part
/// and the per-cloud global part), "decoder", "regression".
std::map<std::string, int64_t> OmnetForwardMacs(const OmnetConfig& c, int64_t n, int64_t m);

}  // namespace regbench::networks
