#pragma once
// RGM (Fu et al., "Robust Point Cloud Registration Framework Based on Deep Graph Matching",
// CVPR 2021; authors' code fukexue/RGM, which carries no licence: this file is written from
// the paper and a reading of their models/ and eval.py, none of their text). One network pass
// ("match") on a source of N and a target of M points:
//  - a static DGCNN (k = 20 neighbours, the point itself included) on the edge features
//    [x_j, x_i] (neighbour, centre): bias-free 1x1 Conv2d 6 -> 64 -> 64 -> 128 -> 256, each
//    BN2d + ReLU and max-pooled over the neighbours; the four pooled maps concatenated are the
//    "node" features (512), a bias-free Conv2d 512 -> 512 + BN + ReLU of them the "edge"
//    features; a point's embedding is [node, edge] (1024);
//  - two graph-matching layers, each: a transformer (one encoder and one decoder layer, 4
//    heads, pre-norm, feed-forward 1024 wide) that embeds each cloud conditioned on the other;
//    a soft adjacency softmax(E^T E / sqrt(d)) of each cloud's embedding; a Siamese graph
//    convolution x' = Â relu(W_a x + b_a) + relu(W_u x + b_u) (Â: the adjacency with columns
//    normalised to sum 1) to 512; a bilinear affinity X ((A + A^T) / 2) Y^T; an instance norm
//    (affine) of the N x M affinity; 20 log-domain Sinkhorn iterations with a slack row and
//    column. After the first layer a cross-graph linear map mixes each cloud's embedding with
//    the other's matched through the soft correspondence: x' = W [x, S y] + b.
//  The last layer's soft correspondence S [N, M] (its row / column sums are the points' inlier
//  mass) is what the loss sees: binary cross-entropy against the ground-truth correspondence.
// Test time (the authors' eval.py with their ModelNet40 crop / jitter configs: ITERATION,
// ITERATION_NUM 2, CYCLE): per direction, `estimate_iterations` times: match, a maximum-weight
// linear assignment on the rows and columns whose mass exceeds `inlier_threshold`, a weighted
// SVD (Kabsch) of the matched pairs, the source moved by it; the last iteration's assignment is
// kept. Both directions (source to target, target to source); the pairs found in both (the
// cycle check) give the final weighted SVD on the original clouds.
//
// Module and parameter names are the keys of the authors' state dict (models/Net.py, less
// DataParallel's "module." prefix), one to one: pointfeaturer.{conv1..5, bn1..5},
// gmattend{0,1}.model.{encoder,decoder}..., gnn_layer_{0,1}.gconv.{a_fc,u_fc},
// affinity_{0,1}.A, InstNorm_layer_{0,1}.{weight,bias} and cross_graph_0.
// Deviations from the authors' code (docs/learned-methods.md, "RGM"):
//  - clouds of different sizes: their correspondence gather (calcorrespondpc) pairs the
//    unmatched rows with the unmatched columns and fails unless N == M; regbench takes the
//    matched pairs only (the unmatched ones have weight 0 in their SVD: the same transform);
//  - the linear assignment is regbench's shortest augmenting paths
//    (networks/families/rgm/assignment.hpp) instead of scipy's (an optimum either way); a
//    step with fewer than 3 matched pairs keeps the cloud where it is (theirs runs the SVD on
//    a zero covariance);
//  - the last iteration's SVD, which their loop computes and discards, is skipped;
//  - fewer points than k: every point is a neighbour (theirs fails);
//  - in training mode Forward runs one match (no assignment) and T is a soft weighted SVD;
//  - `width_divisor` > 1 divides every hidden width (a CPU-trainable size; 1 is theirs).
#include <torch/torch.h>

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "networks/checkpoint/torch_save_reader.hpp"
#include "networks/family_config.hpp"
#include "networks/net.hpp"

namespace regbench::networks {

/// The authors' hyper-parameters (experiments/*_transformer.yaml, utils/config.py), names in
/// comments; the ranges (Validate) are in networks/families/rgm/net.cpp.
struct RgmConfig {
    std::string name = "rgm";      ///< zoo name it came from
    int width_divisor = 1;         ///< every hidden width / this (1: the authors' widths)
    int k = 20;                    ///< DGCNN neighbours, the point itself included (NEIGHBORSNUM)
    int heads = 4;                 ///< transformer heads (n_heads)
    int sinkhorn_iterations = 20;  ///< Sinkhorn iterations (n_iters of sinkhorn_rpm)
    int estimate_iterations = 2;   ///< test-time match + SVD rounds (EVAL.ITERATION_NUM)
    bool cycle = true;             ///< keep the pairs both directions find (EVAL.CYCLE)
    double inlier_threshold = 0.5;  ///< rows / columns with more mass enter the assignment (th)
    double label_dist = 0.05;  ///< training labels: nearest neighbours nearer than this (padth)

    template <class F>
    void Fields(F&& f) {
        f("name", name, "zoo name it came from");
        f("width_divisor", width_divisor,
          "every hidden width / this (1: the authors' 25.0 M parameters; 8: 0.4 M); divides 64");
        f("k", k, "DGCNN neighbours, the point itself included (the authors' NEIGHBORSNUM)");
        f("heads", heads, "transformer attention heads (the authors': 4)");
        f("sinkhorn_iterations", sinkhorn_iterations,
          "log-domain Sinkhorn iterations with slack (the authors': 20)");
        f("estimate_iterations", estimate_iterations,
          "test-time rounds of match, assignment and SVD per direction (EVAL.ITERATION_NUM: 2)");
        f("cycle", cycle, "keep only the pairs both directions find (EVAL.CYCLE)");
        f("inlier_threshold", inlier_threshold,
          "rows and columns of the soft correspondence with more mass enter the assignment");
        f("label_dist", label_dist,
          "training labels: nearest neighbours under the true motion nearer than this match "
          "[unit-sphere units] (the authors' padth)");
    }
    void Validate(ParamCheck& c) const;
};

/// {"arch": "rgm", "name", ...}; every field always present.
nlohmann::json ToJson(const RgmConfig& c);
/// Reads the keys of `j` over the defaults (ParseNetConfig); unknown keys or bad values throw
/// std::invalid_argument naming them (width_divisor must divide 64, heads the widths).
RgmConfig RgmConfigFromJson(const nlohmann::json& j);

/// The hidden widths of a config: DGCNN 64, 64, 128, 256 and its 512 output, the graph
/// features 512 and the transformer's feed-forward 1024, each / width_divisor.
struct RgmWidths {
    int64_t c1, c2, c3, c4, node, edge, gnn, ff;
    explicit RgmWidths(int divisor);
};

/// One transformer's multi-head attention: linears.0..3 (query, key, value, output; with bias).
class RgmAttentionImpl : public torch::nn::Module {
public:
    RgmAttentionImpl(int64_t d, int64_t heads);
    /// x [B, P, d] attends to memory [B, Q, d] -> [B, P, d].
    torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& memory);

private:
    int64_t heads_;
    torch::nn::ModuleList linears_{nullptr};
};
TORCH_MODULE(RgmAttention);

/// The authors' LayerNorm: a_2 (x - mean) / (std + 1e-6) + b_2, std unbiased.
class RgmLayerNormImpl : public torch::nn::Module {
public:
    explicit RgmLayerNormImpl(int64_t d);
    torch::Tensor forward(const torch::Tensor& x);

private:
    torch::Tensor a_2_, b_2_;
};
TORCH_MODULE(RgmLayerNorm);

/// Typed handles of one encoder or decoder layer (the modules are registered on the tree).
struct RgmTransformerLayer {
    RgmAttention self_attn{nullptr}, src_attn{nullptr};  ///< src_attn: decoder only
    torch::nn::Linear w_1{nullptr}, w_2{nullptr};        ///< feed_forward
    std::vector<RgmLayerNorm> norms;                     ///< sublayer.I.norm
    RgmLayerNorm final_norm{nullptr};                    ///< the stack's norm
};

/// One graph-matching layer's transformer: model.encoder (one layer: self_attn, feed_forward,
/// sublayer.{0,1}.norm; then norm) and model.decoder (one layer: self_attn, src_attn,
/// feed_forward, sublayer.{0,1,2}.norm; then norm).
class RgmTransformerImpl : public torch::nn::Module {
public:
    RgmTransformerImpl(int64_t d, int64_t ff, int64_t heads);
    /// Embeddings [B, N, d] and [B, M, d] -> each cloud's embedding given the other, [B, d, N]
    /// and [B, d, M] (the authors' Transformer.forward).
    std::pair<torch::Tensor, torch::Tensor> forward(const torch::Tensor& src,
                                                    const torch::Tensor& tgt);

private:
    RgmTransformerLayer encoder_, decoder_;
};
TORCH_MODULE(RgmTransformer);

class RgmNet : public RegistrationNet {
public:
    explicit RgmNet(const RgmConfig& config);
    /// One match: the soft correspondence S [B, N, M] of the last graph-matching layer.
    torch::Tensor Match(const torch::Tensor& source, const torch::Tensor& target);
    /// Eval mode: the test-time pipeline (header comment); aux "correspondence" [B, N, M] the
    /// final 0/1 pairs and "s" the first match's soft correspondence (what Loss scores). Training
    /// mode: one match, aux "s" [B, N, M], T a soft weighted SVD. Throws std::invalid_argument on
    /// clouds of other shapes.
    NetOutput Forward(const PairBatch& batch) override;
    /// "perm": the authors' PermLoss, binary cross-entropy of S against the ground-truth
    /// correspondence summed over the N x M entries and divided by the batch's source points;
    /// "total" the same. The correspondence: mutual nearest neighbours under T_gt nearer than
    /// label_dist, then (rows in order, then columns) one-sided nearest neighbours nearer than
    /// label_dist whose row and column are both still free.
    LossTerms Loss(const PairBatch& batch, const NetOutput& output) override;
    nlohmann::json Config() const override { return ToJson(config_); }
    const RgmConfig& config() const { return config_; }

private:
    /// DGCNN: points [B, P, 3] -> [node, edge] embeddings [B, P, node + edge].
    torch::Tensor Features(const torch::Tensor& points);
    /// One direction of the test-time pipeline: the 0/1 correspondence [B, N, M]; `first`,
    /// when given, receives the first round's soft correspondence.
    torch::Tensor Direction(const torch::Tensor& source, const torch::Tensor& target,
                            torch::Tensor* first = nullptr);

    RgmConfig config_;
    std::vector<torch::nn::Conv2d> convs_;
    std::vector<torch::nn::BatchNorm2d> bns_;
    std::vector<RgmTransformer> transformers_;
    std::vector<torch::nn::Linear> a_fc_, u_fc_;
    std::vector<torch::Tensor> affinity_;
    std::vector<torch::Tensor> norm_weight_, norm_bias_;  ///< InstNorm_layer_I (affine)
    torch::nn::Linear cross_graph_{nullptr};
};

/// Log-domain Sinkhorn with a slack row and column (the authors' sinkhorn_rpm, slack): log
/// weights [B, N, M] padded with a zero row and column; `iterations` times the N real rows are
/// normalised over all M + 1 columns, then the M real columns over all N + 1 rows. Returns the
/// real block [B, N, M] (log).
torch::Tensor SinkhornSlack(const torch::Tensor& log_alpha, int iterations);

/// exp(SinkhornSlack(log_alpha, iterations)). With autograd that LibTorch composition; without,
/// the fused kernel (networks/families/rgm/kernels.hpp) over log_alpha's own storage (when
/// contiguous), which it overwrites.
torch::Tensor SinkhornSlackExpInPlace(torch::Tensor log_alpha, int iterations);

/// RGM's soft adjacency of a Gram matrix [B, P, P] (E^T E): softmax(scale gram, -1), then each
/// column divided by its sum (F.normalize(p=1, dim=-2), sums clamped at 1e-12). With autograd
/// LibTorch's composition; without, the fused row kernels over gram's own storage.
torch::Tensor SoftAdjacency(torch::Tensor gram, double scale);

/// The weighted Kabsch of the authors' SVDslover: pairs (P_i, Q_i) of P [B, N, 3], Q [B, N, 3]
/// with weights w [B, N] normalised by (sum + 1e-5); T [B, 4, 4] maps P onto Q. A batch entry
/// whose weights sum to 0 gets the identity.
torch::Tensor WeightedRigid(const torch::Tensor& P, const torch::Tensor& Q, const torch::Tensor& w);

/// The 0/1 correspondence [N, M] (float64) of soft weights s [N, M]: the maximum-weight
/// assignment on the rows whose sum exceeds `threshold` and the columns whose sum does
/// (the authors' hungarian with inlier masses).
torch::Tensor AssignInliers(const torch::Tensor& s, double threshold);

/// Multiply-accumulates of one batch-1 Forward (the whole test-time pipeline: 2 x
/// estimate_iterations matches with the cycle, else estimate_iterations) on N source and M
/// target points, by part: "dgcnn" (edge and node convolutions; kNN Gram), "transformer",
/// "adjacency" (E^T E), "gconv", "affinity", "cross_graph" (S y and the linear), "svd" (the
/// weighted covariances). Sinkhorn, softmax, norms and the assignment are not counted.
std::map<std::string, int64_t> RgmForwardMacs(const RgmConfig& c, int64_t n, int64_t m);

}  // namespace regbench::networks
