#pragma once
// REGTR (Yew and Lee, "REGTR: End-to-end Point Cloud Correspondences with Transformers", CVPR
// 2022) as the authors implement it (yewzijian/RegTR, src/models/regtr.py with the ModelNet
// config src/conf/modelnet.yaml): a KPConv encoder per cloud (blocks simple, resnetb, resnetb,
// resnetb_strided, resnetb, resnetb: 15 kernel points, linear influence, sum aggregation,
// per-cloud instance norm, leaky ReLU 0.1; the strided block pools onto a 0.06 voxel grid), a
// linear bottleneck to d_embed, sine position encodings of the superpoints, a pre-norm cross
// encoder (self attention of each cloud, then cross attention to the other, then a feed-forward
// layer, 8 heads, the same weights for both clouds), and per layer an MLP that regresses each
// superpoint's coordinates in the other cloud plus an overlap logit. The pose is the weighted
// Kabsch fit of both directions' correspondences (src superpoints -> their regressed target
// positions, regressed source positions -> tgt superpoints), weights the overlap sigmoids.
//
// Module and parameter names are the keys of the authors' state dict, one to one:
// kpf_encoder.encoder_blocks.I.{KPConv.weights, KPConv.kernel_points, unary1.mlp.weight, ...},
// feat_proj, transformer_encoder.layers.I.{self_attn, multihead_attn, linear1, linear2,
// norm1..3}, transformer_encoder.norm, correspondence_decoder.{coor_mlp, conf_logits_decoder}
// and the two InfoNCE matrices feature_criterion.W and feature_criterion_un.W.
//
// Deviations from the authors' code (docs/learned-methods.md, "REGTR"):
//  - grid subsampling orders the voxels by their integer coordinates (x, then y, then z);
//    the authors' MinkowskiEngine quantisation returns them in a hash order that changes from
//    run to run. The voxels and their barycentres are the same; the order then fixes which
//    superpoints a neighbourhood capped at neighbor_limit keeps;
//  - radius neighbours are the support points strictly nearer than the radius, in index order,
//    the first neighbor_limit of them (the authors' pytorch3d ball_query), found with nanoflann;
//  - each pair is run on its own (no padding); the authors pad a batch, which changes nothing;
//  - only the last layer's pose is computed (the authors compute all six and use the last);
//  - a freshly built network's kernel points are a fixed disposition (the centre, the six
//    axis directions and the eight cube diagonals at 0.66 conv radius); the authors' are an
//    optimised disposition with random noise and rotation, and an imported checkpoint
//    carries theirs (they are in the state dict).
#include <torch/torch.h>

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/params.hpp"
#include "networks/checkpoint/torch_save_reader.hpp"
#include "networks/net.hpp"

namespace regbench::networks {

/// The authors' ModelNet hyper-parameters (src/conf/modelnet.yaml), names in comments; the
/// ranges (Validate) are in networks/families/regtr/net.cpp.
struct RegtrConfig {
    std::string name = "regtr";
    int d_embed = 256;                   ///< d_embed
    int nhead = 8;                       ///< nhead
    int d_feedforward = 1024;            ///< d_feedforward
    int num_encoder_layers = 6;          ///< num_encoder_layers
    int first_feats_dim = 512;           ///< first_feats_dim (the KPConv widths follow from it)
    double first_subsampling_dl = 0.03;  ///< first_subsampling_dl (conv radius = this x 2.75)
    double conv_radius = 2.75;           ///< conv_radius (in units of first_subsampling_dl)
    double kp_extent = 2.0;              ///< KP_extent (in units of first_subsampling_dl)
    int neighbor_limit = 50;             ///< neighborhood_limits (both levels)
    double overlap_radius = 0.0375;      ///< training labels: overlapping when nearer
    double r_p = 0.12;                   ///< InfoNCE positive radius
    double r_n = 0.24;                   ///< InfoNCE negative radius
    double wt_overlap = 1.0;             ///< wt_overlap
    double wt_feature = 0.1;             ///< wt_feature
    double wt_corr = 1.0;                ///< wt_corr

    template <class F>
    void Fields(F&& f) {
        f("name", name, "zoo name it came from");
        f("d_embed", d_embed, "transformer width (the authors' 256)");
        f("nhead", nhead, "attention heads (the authors' 8); divides d_embed");
        f("d_feedforward", d_feedforward, "transformer feed-forward width (the authors' 1024)");
        f("num_encoder_layers", num_encoder_layers,
          "cross-encoder layers (the authors' 6); the last one's output is used");
        f("first_feats_dim", first_feats_dim,
          "KPConv encoder width: the first block outputs half of it, the last twice it (512); a "
          "multiple of 8");
        f("first_subsampling_dl", first_subsampling_dl,
          "voxel of the input level [unit-sphere units]; superpoints on a grid twice as coarse");
        f("conv_radius", conv_radius,
          "KPConv neighbourhood radius in units of first_subsampling_dl (2.75)");
        f("kp_extent", kp_extent,
          "kernel point influence radius in units of first_subsampling_dl (2.0)");
        f("neighbor_limit", neighbor_limit,
          "most neighbours a KPConv neighbourhood keeps (the authors' 50)");
        f("overlap_radius", overlap_radius,
          "training labels: a point overlaps when nearer than this to the other cloud under the "
          "true motion [unit-sphere units]");
        f("r_p", r_p, "InfoNCE: a superpoint's positive is its nearest within this [units]");
        f("r_n", r_n, "InfoNCE: other superpoints nearer than this are ignored [units]; >= r_p");
        f("wt_overlap", wt_overlap, "weight of the overlap BCE loss");
        f("wt_feature", wt_feature, "weight of the InfoNCE feature loss");
        f("wt_corr", wt_corr, "weight of the overlap-weighted L1 correspondence loss");
    }
    void Validate(ParamCheck& c) const;
};

/// {"arch": "regtr", "name", ...}; every field always present.
nlohmann::json ToJson(const RegtrConfig& c);
/// Reads the keys of `j` over the defaults (ParseNetConfig); unknown keys or bad values throw
/// std::invalid_argument naming them.
RegtrConfig RegtrConfigFromJson(const nlohmann::json& j);

/// Grid subsampling of points [N, 3]: the barycentre of the points of each voxel
/// floor(p / dl), the voxels in increasing (x, y, z) integer order. Returns [V, 3].
torch::Tensor GridSubsample(const torch::Tensor& points, double dl);
/// For each query [Q, 3] the indices of the support points [S, 3] strictly nearer than
/// `radius`, in increasing index order, at most `limit` of them; the rest of the row is S (the
/// "shadow" point). Returns [Q, W] int64, W = min(limit, most found + 1): the authors' [Q,
/// limit] less columns that are shadow in every row (exact: they add nothing), one kept while a
/// row is not full (a max-pool still sees the shadow's zero).
torch::Tensor RadiusNeighbors(const torch::Tensor& queries, const torch::Tensor& supports,
                              double radius, int64_t limit);

/// A rigid kernel point convolution (the authors' KPConv, not deformable).
class RegtrKpconvImpl : public torch::nn::Module {
public:
    RegtrKpconvImpl(int64_t in, int64_t out, double radius, double extent);
    /// q [Q, 3], s [S, 3], neighbours [Q, H] (S = shadow), x [S, in] -> [Q, out].
    torch::Tensor forward(const torch::Tensor& q, const torch::Tensor& s, const torch::Tensor& nb,
                          const torch::Tensor& x);
    torch::Tensor weights, kernel_points;
    double extent;
};
TORCH_MODULE(RegtrKpconv);

/// Linear (no bias), instance norm over the cloud's points, leaky ReLU 0.1 (unless no_relu).
class RegtrUnaryImpl : public torch::nn::Module {
public:
    RegtrUnaryImpl(int64_t in, int64_t out, bool relu);
    torch::Tensor forward(const torch::Tensor& x);
    torch::nn::Linear mlp{nullptr};
    bool relu;
};
TORCH_MODULE(RegtrUnary);

/// One block of the KPConv encoder: "simple" (KPConv in -> out / 2) or "resnetb" (unary1,
/// KPConv, unary2, shortcut), strided or not.
class RegtrBlockImpl : public torch::nn::Module {
public:
    RegtrBlockImpl(bool simple, bool strided, int64_t in, int64_t out, double radius,
                   double extent);
    /// features on the support points [S, in] -> [Q, out'].
    torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& q, const torch::Tensor& s,
                          const torch::Tensor& nb);
    bool simple, strided;
    RegtrKpconv kpconv{nullptr};
    RegtrUnary unary1{nullptr}, unary2{nullptr}, shortcut{nullptr};
};
TORCH_MODULE(RegtrBlock);

/// torch.nn.MultiheadAttention's parameters (in_proj_weight, in_proj_bias, out_proj), batch 1.
class RegtrAttentionImpl : public torch::nn::Module {
public:
    RegtrAttentionImpl(int64_t d, int64_t heads);
    /// query [L, d], key [S, d], value [S, d] -> [L, d].
    torch::Tensor forward(const torch::Tensor& q, const torch::Tensor& k, const torch::Tensor& v);
    torch::Tensor in_proj_weight, in_proj_bias;
    torch::nn::Linear out_proj{nullptr};
    int64_t heads;
};
TORCH_MODULE(RegtrAttention);

/// The authors' TransformerCrossEncoderLayer, pre-norm, values with position encodings.
class RegtrCrossLayerImpl : public torch::nn::Module {
public:
    RegtrCrossLayerImpl(int64_t d, int64_t heads, int64_t ff);
    std::pair<torch::Tensor, torch::Tensor> forward(torch::Tensor src, torch::Tensor tgt,
                                                    const torch::Tensor& src_pos,
                                                    const torch::Tensor& tgt_pos);
    RegtrAttention self_attn{nullptr}, multihead_attn{nullptr};
    torch::nn::Linear linear1{nullptr}, linear2{nullptr};
    torch::nn::LayerNorm norm1{nullptr}, norm2{nullptr}, norm3{nullptr};
};
TORCH_MODULE(RegtrCrossLayer);

/// The authors' sine position encoding of 3-D coordinates [P, 3] -> [P, d] (2 pi scale,
/// temperature 10000, d / 3 / 2 * 2 features a coordinate, zero padded).
torch::Tensor RegtrPositionEncoding(const torch::Tensor& xyz, int64_t d);
/// Weighted Kabsch fit (the authors' compute_rigid_transform): a, b [P, 3], w [P] in [0, 1]
/// -> [4, 4] with T a ~ b.
torch::Tensor WeightedKabsch(const torch::Tensor& a, const torch::Tensor& b,
                             const torch::Tensor& w);

class RegtrNet : public RegistrationNet {
public:
    explicit RegtrNet(const RegtrConfig& config);
    /// aux per pair b: "src_kp_b", "tgt_kp_b" (superpoints), "src_pool_b", "tgt_pool_b"
    /// (pooling neighbours), "src_corr_b", "tgt_corr_b" (last layer's regressed coordinates),
    /// "src_overlap_b", "tgt_overlap_b" (its logits), "src_feat_b", "tgt_feat_b" (its
    /// features). Throws std::invalid_argument on clouds of other shapes.
    NetOutput Forward(const PairBatch& batch) override;
    /// The authors' terms on the last layer: "overlap" (BCE of the overlap logits against the
    /// ground-truth overlap pooled onto the superpoints), "feature" (InfoNCE, r_p / r_n),
    /// "corr" (overlap-weighted L1 of the regressed coordinates, both directions), each times
    /// its weight; "total" their sum. The unconditioned-feature InfoNCE has weight 0 in the
    /// authors' config and is not computed.
    LossTerms Loss(const PairBatch& batch, const NetOutput& output) override;
    nlohmann::json Config() const override { return ToJson(config_); }

private:
    /// Superpoints [V, 3], pooling neighbours and features [V, d_embed] of one cloud [N, 3].
    std::tuple<torch::Tensor, torch::Tensor, torch::Tensor> Encode(const torch::Tensor& pts);

    RegtrConfig config_;
    torch::nn::Module kpf_encoder_;
    torch::nn::ModuleList blocks_;
    torch::nn::Linear feat_proj_{nullptr};
    torch::nn::ModuleList layers_;
    torch::nn::LayerNorm final_norm_{nullptr};
    torch::nn::Sequential coor_mlp_{nullptr};
    torch::nn::Linear conf_logits_{nullptr};
    torch::Tensor feature_W_, feature_un_W_;
};

/// Multiply-accumulates of one batch-1 forward on n source and m target points by part:
/// "kpconv" (the kernel point convolutions), "unary" (the encoder's linear layers and the
/// bottleneck), "attention" (projections and the attention products), "feedforward",
/// "heads". Data-dependent counts are taken at their bound: every neighbourhood holds
/// neighbor_limit points and the superpoints are min(points, 700 x points / 717) (the ModelNet
/// 717-point crops give about 700).
std::map<std::string, int64_t> RegtrForwardMacs(const RegtrConfig& c, int64_t n, int64_t m);

}  // namespace regbench::networks
