#include "networks/families/ogmm/net.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "core/params.hpp"
#include "gmm/simd_exp.hpp"
#include "networks/family_config.hpp"
#include "networks/layers/gmm_head.hpp"

namespace regbench::networks {

namespace {

namespace F = torch::nn::functional;
using torch::indexing::Slice;

constexpr const char* kName = "ogmm";
constexpr double kRowMassFloor = 1e-3;       // gamma = Gamma / max(row sum, 1e-3) (authors' code)
constexpr double kMeanDenominator = 1e-5;    // mu, nu = sum gamma x / (sum gamma + 1e-5)
constexpr double kOverlapSumFloor = 1e-4;    // w = op / max(sum op, 1e-4)
constexpr double kKabschRegulariser = 1e-5;  // H + 1e-5 I before the SVD

// [B, n, 3] x [B, m, 3] -> [B, n, m] squared distances, exact (no |a|^2 + |b|^2 - 2ab
// cancellation) and differentiable everywhere, including at zero distance.
torch::Tensor SquaredDistances(const torch::Tensor& a, const torch::Tensor& b) {
    return (a.unsqueeze(2) - b.unsqueeze(1)).pow(2).sum(3);
}

void CheckCloud(const torch::Tensor& x, const char* name) {
    if (!x.defined() || x.dim() != 3 || x.size(2) != 3 || x.size(1) < 1) {
        throw std::invalid_argument(std::string("ogmm: batch.") + name +
                                    " must be a [B, N, 3] tensor");
    }
}

// Weighted cluster averages sum_i gamma_ij x_i / (sum_i gamma_ij + 1e-5): gamma [B, N, J],
// x [B, N, C] -> [B, J, C].
torch::Tensor ClusterAverages(const torch::Tensor& gamma, const torch::Tensor& x) {
    return torch::bmm(gamma.transpose(1, 2), x) / (gamma.sum(1).unsqueeze(2) + kMeanDenominator);
}

// Rotation and translation blocks of T [B, 4, 4].
torch::Tensor RotationOf(const torch::Tensor& T) {
    return T.index({Slice(), Slice(0, 3), Slice(0, 3)});
}
torch::Tensor TranslationOf(const torch::Tensor& T) { return T.index({Slice(), Slice(0, 3), 3}); }

// Welsch terms sum_i (1 - exp(-z_i^2 / 2 alpha^2)) of the nearest-neighbour distances z_i from
// the `count` points of `from` [B, n, 3] ranked highest by `labels` [B, n] to `to` [B, m, 3].
torch::Tensor WelschOfTopLabelled(const torch::Tensor& from, const torch::Tensor& labels,
                                  const torch::Tensor& to, int64_t count, double alpha) {
    const int64_t keep = std::min<int64_t>(count, from.size(1));
    const torch::Tensor idx = std::get<1>(labels.topk(keep, 1));  // [B, keep]
    const torch::Tensor picked = torch::gather(from, 1, idx.unsqueeze(2).expand({-1, -1, 3}));
    const torch::Tensor z2 = std::get<0>(SquaredDistances(picked, to).min(2));  // [B, keep]
    return (1 - torch::exp(-z2 / (2 * alpha * alpha))).sum(1);
}

}  // namespace

// Ranges: the authors' ModelNet config is d 512, 128 anchors and clusters, 4 heads, k 20,
// spe_k 5 (gfmei/ogmm), 10 GMM rounds of 10 Sinkhorn iterations. The bounds are 4 (widths) to
// 100 (rounds) times those: no trained configuration comes near them, and the network built at
// them still fits in memory (emb_dims 65536, the old bound, asked for tens of GB).
void OgmmConfig::Validate(ParamCheck& c) const {
    InRange(c, "emb_dims", emb_dims, 2, 2048);
    c.Require(emb_dims % 2 == 0, "emb_dims", "must be even, got " + std::to_string(emb_dims));
    InRange(c, "anchors", anchors, 1, 4096);
    InRange(c, "clusters", clusters, 3, 4096);  // a rigid fit needs 3 means
    InRange(c, "heads", heads, 1, 64);
    c.Require(emb_dims % heads == 0, "emb_dims", "must be divisible by heads");
    InRange(c, "k", k, 1, 128);
    InRange(c, "spe_k", spe_k, 2, 128);  // the first neighbour is the point itself
    c.Require(attention == "clustered" || attention == "full", "attention",
              "must be \"clustered\" or \"full\", got \"" + attention + "\"");
    InRange(c, "gmm_iterations", gmm_iterations, 1, 1000);
    Positive(c, "sinkhorn_epsilon", sinkhorn_epsilon);
    NonNegative(c, "sinkhorn_threshold", sinkhorn_threshold);
    InRange(c, "sinkhorn_iterations", sinkhorn_iterations, 1, 1000);
    Positive(c, "match_temperature", match_temperature);
    for (const auto& [key, weight] : {std::pair<const char*, double>{"w_pose", w_pose},
                                      {"w_clu", w_clu},
                                      {"w_ovl", w_ovl},
                                      {"w_welsch", w_welsch}}) {
        NonNegative(c, key, weight);
    }
    Positive(c, "nt_xent_temperature", nt_xent_temperature);
    Positive(c, "welsch_alpha", welsch_alpha);
    InRange(c, "welsch_keypoints", welsch_keypoints, 1, 65536);
}

OgmmConfig ParseOgmmConfig(const nlohmann::json& config) {
    return ParseNetConfig<OgmmConfig>(config, kName);
}

nlohmann::json OgmmConfigToJson(const OgmmConfig& config) { return NetConfigJson(config, ""); }

nlohmann::json OgmmNamedConfig(const std::string& name) {
    OgmmConfig c;
    if (name == "ogmm-small") {
        c.emb_dims = 128;
        c.anchors = 32;
        c.clusters = 32;
    } else if (name == "ogmm-tiny") {
        c.emb_dims = 64;
        c.anchors = 16;
        c.clusters = 16;
    } else if (name != "ogmm") {
        throw std::invalid_argument("ogmm: unknown named config '" + name +
                                    "' (known: ogmm, ogmm-small, ogmm-tiny)");
    }
    return OgmmConfigToJson(c);
}

std::shared_ptr<RegistrationNet> MakeOgmmNet(const nlohmann::json& config) {
    return std::make_shared<OgmmNet>(ParseOgmmConfig(config));
}

OverlapGmm FitOverlapGmmTensorOps(const torch::Tensor& xyz, const torch::Tensor& overlap,
                                  int64_t clusters, const GmmFitOptions& options) {
    torch::NoGradGuard no_grad;
    const int64_t batch = xyz.size(0);
    const torch::Tensor w = overlap / overlap.sum(1, true).clamp_min(kOverlapSumFloor);
    const torch::Tensor q =
        torch::full({1, clusters}, 1.0 / static_cast<double>(clusters), xyz.options());
    torch::Tensor mu = torch::gather(
        xyz, 1, FpsCentroid(xyz.transpose(1, 2), clusters).unsqueeze(2).expand({-1, -1, 3}));
    torch::Tensor gamma;
    for (int64_t round = 0; round < options.iterations; ++round) {
        const torch::Tensor cost = torch::cdist(xyz, mu);  // |p_i - mu_j|, not squared
        // Per cloud: the batch-mean stopping rule would make one cloud's fit depend on others.
        std::vector<torch::Tensor> plans;
        for (int64_t b = 0; b < batch; ++b) {
            plans.push_back(LogSinkhorn(cost.slice(0, b, b + 1), w.slice(0, b, b + 1), q,
                                        options.epsilon, options.threshold,
                                        static_cast<int>(options.sinkhorn_iterations)));
        }
        const torch::Tensor plan = torch::nan_to_num(torch::cat(plans, 0), 0.0, 0.0, 0.0);
        gamma = plan / plan.sum(2, true).clamp_min(kRowMassFloor);
        mu = ClusterAverages(gamma, xyz);
    }
    return {gamma, mu, gamma.mean(1)};
}

// One cloud of FitOverlapGmm in plain loops (the CPU path). The tensor-op version calls ~40
// small LibTorch ops per Sinkhorn iteration on a [1, N, J] tensor (two logsumexp, a mean, an
// item() sync); here each iteration is two passes over an N x J double buffer with a branch-free
// exp that vectorises. Same maths; the row update is written in the equivalent form
// u_i = eps (log p_i - LSE_j((v_j - C_ij) / eps)), which drops the u_i / eps that the tensor
// form adds and subtracts again.
namespace {

// u_i = eps * (log_p_i - LSE_j((v_j - C_ij) / eps)) for every row i of cost [n, J].
REGBENCH_SIMD_CLONES void SinkhornRows(const double* cost, const double* v, const double* log_p,
                                       long n, long J, double epsilon, double* scratch, double* u) {
    const double inv = 1.0 / epsilon;
    for (long i = 0; i < n; ++i) {
        const double* c = cost + i * J;
        double m = -std::numeric_limits<double>::infinity();
#pragma omp simd reduction(max : m)
        for (long j = 0; j < J; ++j) {
            const double a = (v[j] - c[j]) * inv;
            scratch[j] = a;
            m = a > m ? a : m;
        }
        double s = 0.0;
#pragma omp simd reduction(+ : s)
        for (long j = 0; j < J; ++j) s += ExpClamped(scratch[j] - m);
        u[i] = epsilon * (log_p[i] - (m + std::log(s)));
    }
}

// v_j = eps * (log_q - LSE_i((u_i - C_ij) / eps)) for every column j of cost [n, J].
REGBENCH_SIMD_CLONES void SinkhornColumns(const double* cost, const double* u, double log_q, long n,
                                          long J, double epsilon, double* column_max,
                                          double* column_sum, double* v) {
    const double inv = 1.0 / epsilon;
    for (long j = 0; j < J; ++j) {
        column_max[j] = -std::numeric_limits<double>::infinity();
        column_sum[j] = 0.0;
    }
    for (long i = 0; i < n; ++i) {
        const double* c = cost + i * J;
#pragma omp simd
        for (long j = 0; j < J; ++j) {
            const double a = (u[i] - c[j]) * inv;
            column_max[j] = a > column_max[j] ? a : column_max[j];
        }
    }
    for (long i = 0; i < n; ++i) {
        const double* c = cost + i * J;
#pragma omp simd
        for (long j = 0; j < J; ++j)
            column_sum[j] += ExpClamped((u[i] - c[j]) * inv - column_max[j]);
    }
    for (long j = 0; j < J; ++j)
        v[j] = epsilon * (log_q - (column_max[j] + std::log(column_sum[j])));
}

// gamma_ij = Gamma_ij / max(sum_j Gamma_ij, 1e-3), Gamma_ij = exp((u_i + v_j - C_ij) / eps),
// the exponent capped at 700 so that finite inputs give a finite plan (what the tensor path's
// nan_to_num guards against cannot arise here).
REGBENCH_SIMD_CLONES void SinkhornPlanRows(const double* cost, const double* u, const double* v,
                                           long n, long J, double epsilon, double* gamma) {
    const double inv = 1.0 / epsilon;
    for (long i = 0; i < n; ++i) {
        const double* c = cost + i * J;
        double* g = gamma + i * J;
        double s = 0.0;
#pragma omp simd reduction(+ : s)
        for (long j = 0; j < J; ++j) {
            const double e = ExpClamped(std::min((u[i] + v[j] - c[j]) * inv, 700.0));
            g[j] = e;
            s += e;
        }
        const double scale = 1.0 / std::max(s, kRowMassFloor);
#pragma omp simd
        for (long j = 0; j < J; ++j) g[j] *= scale;
    }
}

// xyz [n, 3], w [n] (normalised masses), first [J] indices of the initial means; writes gamma
// [n, J] and mu [J, 3].
void FitOverlapGmmCloud(const double* xyz, const double* w, long n, long J, const int64_t* first,
                        const GmmFitOptions& options, double* gamma, double* mu) {
    constexpr double kLogFloor = 1e-8;  // the code's log(p + 1e-8)
    const double eps = options.epsilon;
    std::vector<double> cost(static_cast<size_t>(n * J)), u(static_cast<size_t>(n)),
        v(static_cast<size_t>(J)), log_p(static_cast<size_t>(n)), u_new(static_cast<size_t>(n)),
        v_new(static_cast<size_t>(J)), scratch(static_cast<size_t>(std::max(J, 1L))),
        column_max(static_cast<size_t>(J)), column_sum(static_cast<size_t>(J));
    for (long j = 0; j < J; ++j) {
        for (int d = 0; d < 3; ++d) mu[j * 3 + d] = xyz[first[j] * 3 + d];
    }
    for (long i = 0; i < n; ++i) log_p[i] = std::log(w[i] + kLogFloor);
    const double log_q = std::log(1.0 / static_cast<double>(J) + kLogFloor);
    for (int64_t round = 0; round < options.iterations; ++round) {
        for (long i = 0; i < n; ++i) {  // |p_i - mu_j|, not squared
            for (long j = 0; j < J; ++j) {
                double d2 = 0.0;
                for (int d = 0; d < 3; ++d) {
                    const double diff = xyz[i * 3 + d] - mu[j * 3 + d];
                    d2 += diff * diff;
                }
                cost[i * J + j] = std::sqrt(d2);
            }
        }
        std::fill(u.begin(), u.end(), 0.0);
        std::fill(v.begin(), v.end(), 0.0);
        for (int64_t it = 0; it < options.sinkhorn_iterations; ++it) {
            SinkhornRows(cost.data(), v.data(), log_p.data(), n, J, eps, scratch.data(),
                         u_new.data());
            SinkhornColumns(cost.data(), u_new.data(), log_q, n, J, eps, column_max.data(),
                            column_sum.data(), v_new.data());
            double change = 0.0;
            for (long i = 0; i < n; ++i) change += std::abs(u_new[i] - u[i]);
            for (long j = 0; j < J; ++j) change += std::abs(v_new[j] - v[j]);
            u.swap(u_new);
            v.swap(v_new);
            if (change < options.threshold) break;
        }
        SinkhornPlanRows(cost.data(), u.data(), v.data(), n, J, eps, gamma);
        for (long j = 0; j < J; ++j) {  // mu_j = sum_i gamma_ij p_i / (sum_i gamma_ij + 1e-5)
            double mass = 0.0, sx = 0.0, sy = 0.0, sz = 0.0;
            for (long i = 0; i < n; ++i) {
                const double g = gamma[i * J + j];
                mass += g;
                sx += g * xyz[i * 3];
                sy += g * xyz[i * 3 + 1];
                sz += g * xyz[i * 3 + 2];
            }
            const double denominator = mass + kMeanDenominator;
            mu[j * 3] = sx / denominator;
            mu[j * 3 + 1] = sy / denominator;
            mu[j * 3 + 2] = sz / denominator;
        }
    }
}

}  // namespace

OverlapGmm FitOverlapGmm(const torch::Tensor& xyz, const torch::Tensor& overlap, int64_t clusters,
                         const GmmFitOptions& options) {
    if (!xyz.device().is_cpu() || options.iterations < 1) {
        return FitOverlapGmmTensorOps(xyz, overlap, clusters, options);
    }
    torch::NoGradGuard no_grad;
    // Masses in the input's precision (as the tensor-op path), the fit itself in double.
    const torch::Tensor w = (overlap / overlap.sum(1, true).clamp_min(kOverlapSumFloor))
                                .to(torch::kDouble)
                                .contiguous();
    const torch::Tensor points = xyz.to(torch::kDouble).contiguous();
    const torch::Tensor first = FpsCentroid(xyz.transpose(1, 2), clusters).contiguous();
    const int64_t batch = points.size(0), n = points.size(1);
    torch::Tensor gamma = torch::empty({batch, n, clusters}, points.options());
    torch::Tensor mu = torch::empty({batch, clusters, 3}, points.options());
    for (int64_t b = 0; b < batch; ++b) {
        FitOverlapGmmCloud(points.data_ptr<double>() + b * n * 3, w.data_ptr<double>() + b * n, n,
                           clusters, first.data_ptr<int64_t>() + b * clusters, options,
                           gamma.data_ptr<double>() + b * n * clusters,
                           mu.data_ptr<double>() + b * clusters * 3);
    }
    gamma = gamma.to(xyz.scalar_type());
    return {gamma, mu.to(xyz.scalar_type()), gamma.mean(1)};
}

torch::Tensor KabschTransform(const torch::Tensor& src, const torch::Tensor& dst) {
    const int64_t batch = src.size(0);
    const torch::Tensor src_mean = src.mean(1, true), dst_mean = dst.mean(1, true);  // [B,1,3]
    const torch::Tensor H = torch::bmm((src - src_mean).transpose(1, 2), dst - dst_mean) +
                            kKabschRegulariser * torch::eye(3, src.options());
    const auto [U, S, Vh] = torch::linalg_svd(H, /*full_matrices=*/false);
    torch::Tensor V = Vh.transpose(1, 2);
    const torch::Tensor reflection = torch::det(torch::bmm(V, U.transpose(1, 2))) < 0;
    const torch::Tensor sign = torch::where(reflection, -torch::ones_like(S.select(1, 0)),
                                            torch::ones_like(S.select(1, 0)));
    V = torch::cat({V.slice(2, 0, 2), V.slice(2, 2, 3) * sign.view({batch, 1, 1})}, 2);
    const torch::Tensor R = torch::bmm(V, U.transpose(1, 2));
    const torch::Tensor t = dst_mean.transpose(1, 2) - torch::bmm(R, src_mean.transpose(1, 2));
    const torch::Tensor bottom =
        torch::tensor({0.0, 0.0, 0.0, 1.0}, src.options()).view({1, 1, 4}).expand({batch, 1, 4});
    return torch::cat({torch::cat({R, t}, 2), bottom}, 1);
}

torch::Tensor SoftMatchTransform(const torch::Tensor& mu_p, const torch::Tensor& nu_p,
                                 const torch::Tensor& mu_q, const torch::Tensor& nu_q,
                                 double temperature) {
    const auto unit = F::NormalizeFuncOptions().dim(2);
    const torch::Tensor cos =
        torch::bmm(F::normalize(nu_p, unit), F::normalize(nu_q, unit).transpose(1, 2));
    return KabschTransform(mu_p, torch::bmm(torch::softmax(cos / temperature, 2), mu_q));
}

OgmmNet::OgmmNet(const OgmmConfig& config) : config_(config) {
    CheckNetConfig(config_, kName);
    const int64_t d = config_.emb_dims;
    dgcnn_ = register_module("dgcnn", Dgcnn(d, config_.k));
    if (config_.spe) spe_ = register_module("spe", SphericalEncoding(d, config_.spe_k));
    if (config_.csa) att_s1_ = register_module("att_s1", AttentionalPropagation(d, config_.heads));
    conv3_a_ = register_module("conv3_a", Conv3(d, d, 2 * d));
    att_c_ = register_module("att_c", AttentionalPropagation(d, config_.heads));
    if (config_.osp) {
        proj_ = register_module("proj", Conv2(d, 1, d / 2));
        conv3_b_ = register_module("conv3_b", Conv3(d + 2, d, 2 * d));
        conv3_o_ = register_module("conv3_o", Conv3(d, 1, d / 2));
    }
    if (config_.csa) att_s2_ = register_module("att_s2", AttentionalPropagation(d, config_.heads));
}

nlohmann::json OgmmNet::Config() const { return OgmmConfigToJson(config_); }

torch::Tensor OgmmNet::Anchors(const torch::Tensor& features, const torch::Tensor& xyz,
                               const c10::optional<at::Generator>& generator) {
    if (config_.attention == "full") return features;
    // Clouds smaller than `anchors` use every point (an FPS of all N is a permutation).
    const int64_t n = std::min<int64_t>(config_.anchors, xyz.size(2));
    return GatherColumns(features, FpsRandom(xyz, n, generator));
}

torch::Tensor OgmmNet::SelfAttention(AttentionalPropagation& block, const torch::Tensor& x,
                                     const torch::Tensor& keys, const torch::Tensor& xyz,
                                     const c10::optional<at::Generator>& generator) {
    return block->forward(x, Anchors(keys, xyz, generator)) + x;
}

std::pair<torch::Tensor, torch::Tensor> OgmmNet::OverlapScores(const torch::Tensor& gp,
                                                               const torch::Tensor& gq) {
    // S_ij = cos(Gp_i, Gq_j), no temperature; z = per-point overlap logits.
    const torch::Tensor S =
        torch::bmm(F::normalize(gp, F::NormalizeFuncOptions().dim(1)).transpose(1, 2),
                   F::normalize(gq, F::NormalizeFuncOptions().dim(1)));
    const torch::Tensor zp = proj_(gp), zq = proj_(gq);  // [B, 1, N], [B, 1, M]
    const torch::Tensor row = torch::softmax(S, 2), col = torch::softmax(S, 1);
    // The code pools a cloud's own logits with the other cloud's index (needs N = M); the paper
    // pools the other cloud's logits. N != M can only run the paper's form.
    const bool code_index = !config_.fix_overlap_index && gp.size(2) == gq.size(2);
    const torch::Tensor wp = torch::bmm(row, (code_index ? zp : zq).transpose(1, 2));  // [B,N,1]
    const torch::Tensor wq =
        torch::bmm(col.transpose(1, 2), (code_index ? zq : zp).transpose(1, 2));  // [B,M,1]
    const auto head = [&](const torch::Tensor& g, const torch::Tensor& w, const torch::Tensor& z) {
        return torch::sigmoid(conv3_o_(conv3_b_(torch::cat({g, w.transpose(1, 2), z}, 1))))
            .squeeze(1);
    };
    return {head(gp, wp, zp), head(gq, wq, zq)};
}

NetOutput OgmmNet::Forward(const PairBatch& batch) {
    CheckCloud(batch.source, "source");
    CheckCloud(batch.target, "target");
    if (batch.source.size(0) != batch.target.size(0)) {
        throw std::invalid_argument("ogmm: batch.source and batch.target differ in batch size");
    }
    const torch::Tensor p = batch.source.to(torch::kFloat).transpose(1, 2).contiguous();
    const torch::Tensor q = batch.target.to(torch::kFloat).transpose(1, 2).contiguous();
    // 1-3: DGCNN features and spherical positional encoding.
    const torch::Tensor fp = dgcnn_(p), fq = dgcnn_(q);
    torch::Tensor xp = config_.spe ? fp + spe_(p) : fp;
    torch::Tensor xq = config_.spe ? fq + spe_(q) : fq;
    // 4-5: clustered self-attention; its anchors are taken from F, not X.
    if (config_.csa) {
        const torch::Tensor ap = Anchors(fp, p, batch.generator),
                            aq = Anchors(fq, q, batch.generator);
        xp = att_s1_(xp, ap) + xp;
        xq = att_s1_(xq, aq) + xq;
    }
    xp = conv3_a_(xp);
    xq = conv3_a_(xq);
    // 6: cross-attention to the other cloud's anchors (one module, both directions).
    const torch::Tensor bp = Anchors(xp, p, batch.generator), bq = Anchors(xq, q, batch.generator);
    const torch::Tensor gp = att_c_(xp, bq) + xp, gq = att_c_(xq, bp) + xq;
    // 7: overlap scores.
    torch::Tensor op, oq;
    if (config_.osp) {
        std::tie(op, oq) = OverlapScores(gp, gq);
    } else {
        op = torch::ones({p.size(0), p.size(2)}, p.options());
        oq = torch::ones({q.size(0), q.size(2)}, q.options());
    }
    // 8: second self-attention gives the final point features f*.
    const torch::Tensor fsp = config_.csa ? SelfAttention(att_s2_, gp, gp, p, batch.generator) : gp;
    const torch::Tensor fsq = config_.csa ? SelfAttention(att_s2_, gq, gq, q, batch.generator) : gq;
    // 9: overlap-guided GMM fit in xyz (no gradient), cluster features with gradient.
    const GmmFitOptions fit{config_.gmm_iterations, config_.sinkhorn_epsilon,
                            config_.sinkhorn_threshold, config_.sinkhorn_iterations};
    const OverlapGmm gmm_p = FitOverlapGmm(batch.source.to(torch::kFloat), op.detach(),
                                           std::min(config_.clusters, p.size(2)), fit);
    const OverlapGmm gmm_q = FitOverlapGmm(batch.target.to(torch::kFloat), oq.detach(),
                                           std::min(config_.clusters, q.size(2)), fit);
    const torch::Tensor nu_p = ClusterAverages(gmm_p.gamma, fsp.transpose(1, 2));
    const torch::Tensor nu_q = ClusterAverages(gmm_q.gamma, fsq.transpose(1, 2));
    // 10: soft matches of the cluster features, Kabsch from mu_p to the matched mu_q.
    NetOutput out;
    out.T = SoftMatchTransform(gmm_p.mu, nu_p, gmm_q.mu, nu_q, config_.match_temperature);
    out.aux = {
        {"overlap_source", op},        {"overlap_target", oq},   {"gamma_source", gmm_p.gamma},
        {"gamma_target", gmm_q.gamma}, {"mu_source", gmm_p.mu},  {"mu_target", gmm_q.mu},
        {"pi_source", gmm_p.pi},       {"pi_target", gmm_q.pi},  {"nu_source", nu_p},
        {"nu_target", nu_q},           {"features_source", fsp}, {"features_target", fsq}};
    return out;
}

torch::Tensor OgmmNet::ClusterLoss(const torch::Tensor& xyz, const torch::Tensor& mu,
                                   const torch::Tensor& nu, const torch::Tensor& features) const {
    const int64_t batch = mu.size(0), clusters = mu.size(1);
    torch::Tensor nearest;  // [B, J] input point nearest each mean
    {
        torch::NoGradGuard no_grad;
        nearest = std::get<1>(SquaredDistances(mu, xyz).min(2));
    }
    const auto unit = F::NormalizeFuncOptions().dim(2);
    const torch::Tensor a = F::normalize(GatherColumns(features, nearest).transpose(1, 2), unit);
    const torch::Tensor b = F::normalize(nu, unit);
    // NT-Xent over the 2J vectors: a_j's positive is b_j (and back), every other vector is a
    // negative, self-similarity excluded.
    const torch::Tensor z = torch::cat({a, b}, 1);  // [B, 2J, d]
    const auto on = [&](torch::Dtype type) {
        return torch::TensorOptions(type).device(z.device());
    };
    const torch::Tensor self = torch::eye(2 * clusters, on(torch::kBool)).unsqueeze(0);
    const torch::Tensor logits = (torch::bmm(z, z.transpose(1, 2)) / config_.nt_xent_temperature)
                                     .masked_fill(self, -std::numeric_limits<double>::infinity());
    const torch::Tensor positive =
        torch::cat({torch::arange(clusters, 2 * clusters, on(torch::kLong)),
                    torch::arange(0, clusters, on(torch::kLong))})
            .repeat({batch});
    return F::cross_entropy(logits.reshape({batch * 2 * clusters, 2 * clusters}), positive);
}

LossTerms OgmmNet::Loss(const PairBatch& batch, const NetOutput& output) {
    if (!batch.T_gt.defined()) throw std::invalid_argument("ogmm: loss needs batch.T_gt");
    const bool need_labels = (config_.osp && config_.w_ovl > 0) || config_.w_welsch > 0;
    if (need_labels && (!batch.source_overlap.defined() || !batch.target_overlap.defined())) {
        throw std::invalid_argument(
            "ogmm: loss needs batch.source_overlap and batch.target_overlap labels (L_ovl, L_W)");
    }
    const torch::Tensor R = RotationOf(output.T), t = TranslationOf(output.T);
    const torch::Tensor T_gt = batch.T_gt.to(output.T.dtype());
    LossTerms terms;
    if (config_.w_pose > 0) {
        const torch::Tensor I = torch::eye(3, R.options()).expand_as(R);
        terms["pose"] = F::mse_loss(torch::bmm(R.transpose(1, 2), RotationOf(T_gt)), I) +
                        F::mse_loss(t, TranslationOf(T_gt));
    }
    if (config_.w_clu > 0) {
        const torch::Tensor src = batch.source.to(torch::kFloat);
        const torch::Tensor tgt = batch.target.to(torch::kFloat);
        terms["clu"] =
            0.5 * (ClusterLoss(src, output.aux.at("mu_source"), output.aux.at("nu_source"),
                               output.aux.at("features_source")) +
                   ClusterLoss(tgt, output.aux.at("mu_target"), output.aux.at("nu_target"),
                               output.aux.at("features_target")));
    }
    if (config_.osp && config_.w_ovl > 0) {
        terms["ovl"] = F::mse_loss(
            torch::cat({output.aux.at("overlap_source"), output.aux.at("overlap_target")}, 1),
            torch::cat({batch.source_overlap, batch.target_overlap}, 1).to(torch::kFloat));
    }
    if (config_.w_welsch > 0) {
        const torch::Tensor src = batch.source.to(torch::kFloat);
        const torch::Tensor tgt = batch.target.to(torch::kFloat);
        const torch::Tensor moved = torch::bmm(src, R.transpose(1, 2)) + t.unsqueeze(1);
        const auto so = batch.source_overlap.to(torch::kFloat);
        const auto to = batch.target_overlap.to(torch::kFloat);
        terms["welsch"] =
            (WelschOfTopLabelled(moved, so, tgt, config_.welsch_keypoints, config_.welsch_alpha) +
             WelschOfTopLabelled(tgt, to, moved, config_.welsch_keypoints, config_.welsch_alpha))
                .mean();
    }
    const std::map<std::string, double> weights = {{"pose", config_.w_pose},
                                                   {"clu", config_.w_clu},
                                                   {"ovl", config_.w_ovl},
                                                   {"welsch", config_.w_welsch}};
    torch::Tensor total = torch::zeros({}, output.T.options());
    for (auto& [name, value] : terms) {
        value = torch::nan_to_num(value, 0.0, 0.0, 0.0);  // the code's NaN -> 0
        total = total + weights.at(name) * value;
    }
    terms["total"] = total;
    return terms;
}

}  // namespace regbench::networks
