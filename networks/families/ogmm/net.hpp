#pragma once
// OGMM (Mei et al., WACV 2023) as the authors' code runs it: DGCNN features plus a spherical
// positional encoding, clustered self-attention on FPS anchors, cross-attention, an overlap
// head, an overlap-weighted Sinkhorn GMM fit in xyz, soft matching of the cluster features and
// a closed-form (Kabsch) transform. Every ablation of the paper is a field of OgmmConfig; see
// docs/learned-methods.md for the architecture, the paper-vs-code choices and the measured cost.
#include <torch/torch.h>

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "core/params.hpp"
#include "networks/layers/layers.hpp"
#include "networks/net.hpp"

namespace regbench::networks {

/// OGMM architecture and loss configuration. Defaults are the authors' ModelNet config; the
/// ranges (Validate) are in networks/families/ogmm/net.cpp.
struct OgmmConfig {
    int64_t emb_dims = 512;  ///< feature width d (even, divisible by `heads`)
    int64_t anchors = 128;   ///< FPS anchors per attention block ("clusters" of the attention)
    int64_t clusters = 128;  ///< GMM components J fitted per cloud
    int64_t heads = 4;       ///< attention heads
    int64_t k = 20;          ///< DGCNN neighbours (the point itself included)
    int64_t spe_k = 5;       ///< neighbours of the SPE angle branch (self included)
    bool spe = true;         ///< spherical positional encoding added to the DGCNN features
    bool csa = true;         ///< the two (clustered) self-attention blocks; off keeps CONV3_a
    std::string attention = "clustered";  ///< "clustered" (FPS anchors) or "full" (all points)
    bool osp = true;                      ///< overlap scores; off: every point weighs 1, no L_ovl
    bool fix_overlap_index = false;       ///< paper's overlap indexing instead of the code's
    int64_t gmm_iterations = 10;          ///< Sinkhorn k-means rounds of the GMM fit
    double sinkhorn_epsilon = 0.01;       ///< entropic regularisation of the GMM fit's Sinkhorn
    double sinkhorn_threshold = 0.01;     ///< Sinkhorn stops when sum |du| + sum |dv| is below
    int64_t sinkhorn_iterations = 10;     ///< Sinkhorn iterations per GMM round (at most)
    double match_temperature = 0.05;      ///< softmax(cos / T) matching of cluster features
    double w_pose = 10.0;                 ///< weight of L_pose
    double w_clu = 1.0;                   ///< weight of L_clu (NT-Xent)
    double w_ovl = 1.0;                   ///< weight of L_ovl (MSE on overlap scores)
    double w_welsch = 0.01;               ///< weight of L_W (Welsch on top-labelled points)
    double nt_xent_temperature = 0.1;     ///< tau of L_clu
    double welsch_alpha = 10.0;           ///< alpha of the Welsch loss (the code's `mu`)
    int64_t welsch_keypoints = 512;       ///< top-labelled points per cloud in L_W (min with N)

    template <class F>
    void Fields(F&& f) {
        f("emb_dims", emb_dims, "feature width d (even, divisible by heads)");
        f("anchors", anchors, "FPS anchors each clustered attention block attends to");
        f("clusters", clusters, "GMM components J fitted per cloud");
        f("heads", heads, "attention heads");
        f("k", k, "DGCNN neighbours (the point itself included)");
        f("spe_k", spe_k, "neighbours of the spherical positional encoding's angle branch");
        f("spe", spe, "spherical positional encoding added to the DGCNN features (ablation)");
        f("csa", csa, "the two self-attention blocks; false keeps CONV3_a only (ablation)");
        f("attention", attention,
          "\"clustered\" (FPS anchors) or \"full\" (every point); same weights");
        f("osp", osp, "overlap scores; false weighs every point 1 and drops L_ovl (ablation)");
        f("fix_overlap_index", fix_overlap_index,
          "the paper's overlap indexing instead of the authors' code's");
        f("gmm_iterations", gmm_iterations,
          "Sinkhorn k-means rounds of the overlap-guided GMM fit");
        f("sinkhorn_epsilon", sinkhorn_epsilon,
          "entropic regularisation of the GMM fit's Sinkhorn");
        f("sinkhorn_threshold", sinkhorn_threshold,
          "Sinkhorn stops when sum |du| + sum |dv| is below this");
        f("sinkhorn_iterations", sinkhorn_iterations,
          "Sinkhorn iterations per GMM round (at most)");
        f("match_temperature", match_temperature,
          "softmax temperature of the cluster-feature matching");
        f("w_pose", w_pose, "weight of L_pose");
        f("w_clu", w_clu, "weight of L_clu (NT-Xent on cluster features)");
        f("w_ovl", w_ovl, "weight of L_ovl (MSE on overlap scores)");
        f("w_welsch", w_welsch, "weight of L_W (Welsch on the top-labelled points)");
        f("nt_xent_temperature", nt_xent_temperature, "tau of L_clu");
        f("welsch_alpha", welsch_alpha, "alpha of the Welsch loss (the authors' mu)");
        f("welsch_keypoints", welsch_keypoints, "top-labelled points per cloud in L_W (at most N)");
    }
    void Validate(ParamCheck& c) const;
};

/// Parses and validates a config (ParseNetConfig: "arch" and "name" allowed); unknown keys,
/// wrong types and bad values throw std::invalid_argument naming the key. Absent keys keep
/// OgmmConfig's defaults.
OgmmConfig ParseOgmmConfig(const nlohmann::json& config);
/// Every field; no "arch" (OGMM's checkpoints predate the key).
nlohmann::json OgmmConfigToJson(const OgmmConfig& config);

/// The named configs: "ogmm" (authors' code: d 512, 128 anchors, J 128), "ogmm-small"
/// (d 128, 32, 32) and "ogmm-tiny" (d 64, 16, 16). Throws naming an unknown name.
nlohmann::json OgmmNamedConfig(const std::string& name);

/// Builds an OgmmNet from a (validated) JSON config.
std::shared_ptr<RegistrationNet> MakeOgmmNet(const nlohmann::json& config);

/// Result of the overlap-guided GMM fit of one batch of clouds (no gradient).
struct OverlapGmm {
    torch::Tensor gamma;  ///< [B, N, J] responsibilities (rows sum to 1 unless clipped)
    torch::Tensor mu;     ///< [B, J, 3] cluster means
    torch::Tensor pi;     ///< [B, J] mixture weights mean_i gamma_ij (unused by the transform)
};

/// Options of FitOverlapGmm (the Sinkhorn k-means of the authors' code).
struct GmmFitOptions {
    int64_t iterations = 10;           ///< rounds of assignment + mean update
    double epsilon = 0.01;             ///< Sinkhorn regularisation
    double threshold = 0.01;           ///< Sinkhorn stop threshold
    int64_t sinkhorn_iterations = 10;  ///< Sinkhorn iterations per round (at most)
};

/// Fits J clusters to xyz [B, N, 3] with point masses overlap / sum(overlap) (overlap [B, N],
/// >= 0): means start at FpsCentroid; each round costs |p_i - mu_j| (not squared), Sinkhorn
/// with marginals (w, 1/J) gives Gamma (NaN -> 0, per cloud so results do not depend on the
/// batch), gamma_ij = Gamma_ij / max(sum_j Gamma_ij, 1e-3) and mu_j = sum_i gamma_ij p_i /
/// (sum_i gamma_ij + 1e-5). Runs without gradient.
OverlapGmm FitOverlapGmm(const torch::Tensor& xyz, const torch::Tensor& overlap, int64_t clusters,
                         const GmmFitOptions& options = {});

/// FitOverlapGmm written as LibTorch tensor ops: the path for CUDA tensors, and on the CPU the
/// reference that tests hold the loop version (FitOverlapGmm on CPU tensors) to.
OverlapGmm FitOverlapGmmTensorOps(const torch::Tensor& xyz, const torch::Tensor& overlap,
                                  int64_t clusters, const GmmFitOptions& options = {});

/// Unweighted Kabsch between matched point sets src, dst [B, J, 3] as the authors' code runs
/// it: H = sum (s_i - s_mean)(d_i - d_mean)^T + 1e-5 I = U S V^T, R = V U^T (V's third column
/// negated when det < 0), t = d_mean - R s_mean. Returns T [B, 4, 4]; differentiable.
torch::Tensor KabschTransform(const torch::Tensor& src, const torch::Tensor& dst);

/// Soft matching of cluster features and the closed-form transform (the code's step 10):
/// Sm = softmax_j(cos(nu_p_i, nu_q_j) / temperature), y_i = sum_j Sm_ij mu_q_j, then
/// KabschTransform(mu_p, y). mu [B, J, 3], nu [B, J, C]; returns T [B, 4, 4].
torch::Tensor SoftMatchTransform(const torch::Tensor& mu_p, const torch::Tensor& nu_p,
                                 const torch::Tensor& mu_q, const torch::Tensor& nu_q,
                                 double temperature);

/// The OGMM network. Forward() stores in NetOutput.aux: overlap_source [B, N],
/// overlap_target [B, M] (overlap scores in (0, 1), ones with osp off), gamma_source/target
/// [B, N|M, J], mu_source/target [B, J, 3], pi_source/target [B, J], nu_source/target [B, J, d]
/// (cluster features) and features_source/target [B, d, N|M] (the final point features f*).
class OgmmNet : public RegistrationNet {
public:
    explicit OgmmNet(const OgmmConfig& config);
    NetOutput Forward(const PairBatch& batch) override;
    /// Terms "pose", "clu", "ovl", "welsch" (only those with a non-zero weight) and "total" =
    /// w_pose pose + w_clu clu + w_ovl ovl + w_welsch welsch; a NaN term counts as 0. Needs
    /// T_gt, and overlap labels when L_ovl or L_W are on.
    LossTerms Loss(const PairBatch& batch, const NetOutput& output) override;
    nlohmann::json Config() const override;
    const OgmmConfig& config() const { return config_; }

private:
    torch::Tensor Anchors(const torch::Tensor& features, const torch::Tensor& xyz,
                          const c10::optional<at::Generator>& generator);
    torch::Tensor SelfAttention(AttentionalPropagation& block, const torch::Tensor& x,
                                const torch::Tensor& keys, const torch::Tensor& xyz,
                                const c10::optional<at::Generator>& generator);
    std::pair<torch::Tensor, torch::Tensor> OverlapScores(const torch::Tensor& gp,
                                                          const torch::Tensor& gq);
    torch::Tensor ClusterLoss(const torch::Tensor& xyz, const torch::Tensor& mu,
                              const torch::Tensor& nu, const torch::Tensor& features) const;

    OgmmConfig config_;
    Dgcnn dgcnn_{nullptr};
    SphericalEncoding spe_{nullptr};
    AttentionalPropagation att_s1_{nullptr}, att_c_{nullptr}, att_s2_{nullptr};
    Conv3 conv3_a_{nullptr}, conv3_b_{nullptr}, conv3_o_{nullptr};
    Conv2 proj_{nullptr};
};

}  // namespace regbench::networks
