#pragma once
// DeepGMR (Yuan et al., ECCV 2020) in two forms, one class: the original (PointNet on RRI or
// centred-xyz features, the transform loss of the original code) and the OGMM paper's variant
// (OGMM's static DGCNN features, a CONV3 head, the DCP-style pose loss). See
// docs/learned-methods.md.
#include <torch/torch.h>

#include <nlohmann/json.hpp>
#include <string>

#include "core/enum_names.hpp"
#include "core/params.hpp"
#include "networks/families/deepgmr/rri.hpp"
#include "networks/layers/layers.hpp"
#include "networks/net.hpp"

namespace regbench::networks {

/// What the per-point encoder sees and which encoder it is.
enum class DeepGmrFeatures {
    kRri,    ///< original: PointNet on 4k RRI features of the centred cloud
    kXyz,    ///< original: PointNet on the centred xyz
    kDgcnn,  ///< OGMM paper: OGMM's static DGCNN on raw xyz, CONV3 head
};
REGBENCH_CHOICES(DeepGmrFeatures, {{DeepGmrFeatures::kRri, "rri"},
                                   {DeepGmrFeatures::kXyz, "xyz"},
                                   {DeepGmrFeatures::kDgcnn, "dgcnn"}})

/// Training loss.
enum class DeepGmrLoss {
    kTransform,  ///< original: mean((T12 T_gt^-1 - I)^2) + mean((T21 T_gt - I)^2)
    kPose,       ///< DCP style: mean((R^T R_gt - I)^2) + mean((t - t_gt)^2)
};
REGBENCH_CHOICES(DeepGmrLoss,
                 {{DeepGmrLoss::kTransform, "transform"}, {DeepGmrLoss::kPose, "pose"}})

/// The ranges (Validate) are in networks/families/deepgmr/net.cpp.
struct DeepGmrConfig {
    std::string name = "deepgmr-orig";                 ///< zoo name it came from
    DeepGmrFeatures features = DeepGmrFeatures::kRri;  ///< encoder input / kind
    int clusters = 16;                                 ///< J, mixture components
    int rri_k = 20;                                    ///< RRI neighbours (kRri)
    int d_model = 1024;  ///< PointNet feature width (kRri, kXyz; the original's --d_model);
                         ///< written to JSON only when not 1024, so older configs stay equal
    RriVariant rri_variant = RriVariant::kCuda;  ///< phi orientation (kRri)
    int emb_dims = 512;                          ///< DGCNN feature width (kDgcnn)
    int dgcnn_k = 20;                            ///< DGCNN neighbours, self included (kDgcnn)
    int head_hidden = 256;                       ///< CONV3 head hidden width (kDgcnn)
    DeepGmrLoss loss = DeepGmrLoss::kTransform;  ///< training loss

    template <class F>
    void Fields(F&& f) {
        f("name", name, "zoo name it came from");
        f("features", features,
          "\"rri\" (original: PointNet on RRI features), \"xyz\" (original on centred xyz) or "
          "\"dgcnn\" (the OGMM paper's variant: DGCNN, CONV3 head)");
        f("clusters", clusters, "GMM components J");
        f("rri_k", rri_k, "RRI neighbours (features rri)");
        f("d_model", d_model,
          "PointNet feature width (rri, xyz; the original's --d_model; written only when not "
          "1024)");
        f("rri_variant", rri_variant, "RRI phi orientation: cuda (released models) or numpy");
        f("emb_dims", emb_dims, "DGCNN feature width (features dgcnn)");
        f("dgcnn_k", dgcnn_k, "DGCNN neighbours, the point itself included (features dgcnn)");
        f("head_hidden", head_hidden, "CONV3 head hidden width (features dgcnn)");
        f("loss", loss,
          "\"transform\" (original: T12 and T21 against T_gt) or \"pose\" (DCP style: rotation "
          "and translation)");
    }
    void Validate(ParamCheck& c) const;
};

/// {"arch": "deepgmr", "name", "features", "clusters", ...}; every field present but d_model
/// at 1024.
nlohmann::json ToJson(const DeepGmrConfig& c);
/// Reads the keys of `j` over the defaults (ParseNetConfig); unknown keys or bad values throw
/// std::invalid_argument naming them.
DeepGmrConfig DeepGmrConfigFromJson(const nlohmann::json& j);

class DeepGmrNet : public RegistrationNet {
public:
    explicit DeepGmrNet(const DeepGmrConfig& config);
    /// aux: "T21" [B,4,4], "gamma_source"/"gamma_target" [B,N,J], "pi_source"/"pi_target" [B,J].
    NetOutput Forward(const PairBatch& batch) override;
    /// "total" plus the two terms ("T12", "T21" or "rotation", "translation").
    LossTerms Loss(const PairBatch& batch, const NetOutput& output) override;
    nlohmann::json Config() const override { return ToJson(config_); }
    /// Soft assignments gamma [B, N, J] of one cloud [B, N, 3].
    torch::Tensor Assign(const torch::Tensor& xyz);

private:
    DeepGmrConfig config_;
    torch::nn::Sequential encoder_{nullptr};  // PointNet local features (kRri, kXyz)
    torch::nn::Sequential decoder_{nullptr};  // PointNet segmentation head (kRri, kXyz)
    Dgcnn dgcnn_{nullptr};                    // OGMM's static DGCNN (kDgcnn)
    Conv3 head_{nullptr};                     // CONV3 emb -> J (kDgcnn)
};

}  // namespace regbench::networks
