#pragma once
// Differentiable GMM pieces shared by DeepGMR and OGMM (LibTorch). Points are row vectors
// [B, N, 3]; float32 like the authors' code (DeepGMR's GMM parameter estimation from soft
// assignments and OGMM's overlap-weighted variant).
#include <torch/torch.h>

namespace regbench::networks {

/// Mixture parameters from soft assignments gamma [B, N, J] and points xyz [B, N, 3]
/// (DeepGMR section 3): pi_j = sum_i gamma_ij / N, mu_j = sum_i gamma_ij x_i / (N pi_j),
/// s_j = sum_i gamma_ij |x_i - mu_j|^2 / (N pi_j): the total variance, as the code does.
struct GmmParams {
    torch::Tensor pi;     ///< [B, J]
    torch::Tensor mu;     ///< [B, J, 3]
    torch::Tensor sigma;  ///< [B, J] isotropic total variance s_j
};
GmmParams ComputeGmmParams(const torch::Tensor& gamma, const torch::Tensor& xyz);

/// DeepGMR's closed-form registration T [B, 4, 4] mapping the source mixture onto the target
/// mixture: centroids weighted by the source pi, M = sum_j (pi_j / s_t,j)(mu_s,j - c_s)
/// (mu_t,j - c_t)^T, R = V diag(1, 1, det(V U^T)) U^T, t = c_t - R c_s (not the exact weighted
/// minimiser, replicated as the code runs it).
torch::Tensor GmmRegister(const torch::Tensor& pi_s, const torch::Tensor& mu_s,
                          const torch::Tensor& mu_t, const torch::Tensor& sigma_t);

/// Log-domain Sinkhorn (OGMM section 1): cost C [B, N, M], marginals p [B, N], q [B, M].
/// u, v start at 0; each iteration updates u then v; stops when the batch mean of
/// sum |du| + sum |dv| < threshold or after max_iterations. Returns Gamma = exp((-C + u + v) /
/// eps).
torch::Tensor LogSinkhorn(const torch::Tensor& cost, const torch::Tensor& p, const torch::Tensor& q,
                          double epsilon = 0.01, double threshold = 0.01, int max_iterations = 10);

}  // namespace regbench::networks
