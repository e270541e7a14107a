#include "networks/layers/gmm_head.hpp"

namespace regbench::networks {

GmmParams ComputeGmmParams(const torch::Tensor& gamma, const torch::Tensor& xyz) {
    TORCH_CHECK(gamma.dim() == 3 && xyz.dim() == 3 && xyz.size(2) == 3,
                "ComputeGmmParams: expected gamma [B,N,J] and xyz [B,N,3]");
    TORCH_CHECK(gamma.size(0) == xyz.size(0) && gamma.size(1) == xyz.size(1),
                "ComputeGmmParams: gamma and xyz disagree on B or N");
    const double n = static_cast<double>(xyz.size(1));
    GmmParams g;
    const torch::Tensor mass = gamma.sum(1);  // [B, J] = N pi
    g.pi = mass / n;
    g.mu = torch::bmm(gamma.transpose(1, 2), xyz) / mass.unsqueeze(2);  // [B, J, 3]
    // |x_i - mu_j|^2 for every i, j: [B, N, J]
    const torch::Tensor d2 = (xyz.unsqueeze(2) - g.mu.unsqueeze(1)).pow(2).sum(3);
    g.sigma = (gamma * d2).sum(1) / mass;
    return g;
}

torch::Tensor GmmRegister(const torch::Tensor& pi_s, const torch::Tensor& mu_s,
                          const torch::Tensor& mu_t, const torch::Tensor& sigma_t) {
    TORCH_CHECK(mu_s.sizes() == mu_t.sizes(), "GmmRegister: mu_s and mu_t differ in shape");
    const torch::Tensor w = pi_s.unsqueeze(2);          // [B, J, 1]
    const torch::Tensor c_s = (w * mu_s).sum(1, true);  // [B, 1, 3]
    const torch::Tensor c_t = (w * mu_t).sum(1, true);
    const torch::Tensor weights = (pi_s / sigma_t).unsqueeze(2);  // [B, J, 1]
    const torch::Tensor M = torch::bmm(((mu_s - c_s) * weights).transpose(1, 2), mu_t - c_t);
    const auto svd = torch::linalg_svd(M, /*full_matrices=*/true);
    const torch::Tensor U = std::get<0>(svd);
    const torch::Tensor V = std::get<2>(svd).transpose(1, 2);  // linalg::svd returns V^T
    const torch::Tensor det = torch::det(torch::bmm(V, U.transpose(1, 2)));
    torch::Tensor D = torch::eye(3, M.options()).repeat({M.size(0), 1, 1});
    D.index_put_({torch::indexing::Slice(), 2, 2}, det);
    const torch::Tensor R = torch::bmm(torch::bmm(V, D), U.transpose(1, 2));
    const torch::Tensor t = c_t.transpose(1, 2) - torch::bmm(R, c_s.transpose(1, 2));  // [B, 3, 1]
    torch::Tensor T = torch::eye(4, M.options()).repeat({M.size(0), 1, 1});
    T.index_put_(
        {torch::indexing::Slice(), torch::indexing::Slice(0, 3), torch::indexing::Slice(0, 3)}, R);
    T.index_put_(
        {torch::indexing::Slice(), torch::indexing::Slice(0, 3), torch::indexing::Slice(3, 4)}, t);
    return T;
}

torch::Tensor LogSinkhorn(const torch::Tensor& cost, const torch::Tensor& p, const torch::Tensor& q,
                          double epsilon, double threshold, int max_iterations) {
    constexpr double kLogFloor = 1e-8;  // the code's log(p + 1e-8)
    torch::Tensor u = torch::zeros_like(p);
    torch::Tensor v = torch::zeros_like(q);
    const torch::Tensor log_p = torch::log(p + kLogFloor);
    const torch::Tensor log_q = torch::log(q + kLogFloor);
    const auto kernel = [&](const torch::Tensor& uu, const torch::Tensor& vv) {
        return (-cost + uu.unsqueeze(2) + vv.unsqueeze(1)) / epsilon;
    };
    for (int it = 0; it < max_iterations; ++it) {
        const torch::Tensor u_prev = u;
        const torch::Tensor v_prev = v;
        u = u + epsilon * (log_p - torch::logsumexp(kernel(u, v), 2));
        v = v + epsilon * (log_q - torch::logsumexp(kernel(u, v), 1));
        const double change =
            ((u - u_prev).abs().sum(1) + (v - v_prev).abs().sum(1)).mean().item<double>();
        if (change < threshold) break;
    }
    return torch::exp(kernel(u, v));
}

}  // namespace regbench::networks
