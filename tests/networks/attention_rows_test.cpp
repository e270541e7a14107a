#include "networks/layers/attention_rows.hpp"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cstdint>
#include <tuple>

namespace regbench::networks {
namespace {

/// The LibTorch composition: per head softmax(q_h k_h^T) v_h, heads side by side (what
/// torch.nn.MultiheadAttention does between its projections, q already scaled).
torch::Tensor Composed(const torch::Tensor& q, const torch::Tensor& k, const torch::Tensor& v,
                       int64_t heads) {
    const int64_t L = q.size(0), S = k.size(0), d = q.size(1), hd = d / heads;
    const torch::Tensor qh = q.view({L, heads, hd}).transpose(0, 1);
    const torch::Tensor kh = k.view({S, heads, hd}).transpose(0, 1);
    const torch::Tensor vh = v.view({S, heads, hd}).transpose(0, 1);
    const torch::Tensor a = torch::softmax(torch::bmm(qh, kh.transpose(1, 2)), -1);
    return torch::bmm(a, vh).transpose(0, 1).reshape({L, d});
}

TEST(AttentionRows, EqualsTheLibTorchComposition) {
    // Shapes: regtr-small's (4 heads of 16), an odd head width and S not a multiple of the
    // 4-row step, one head, one key; scores spread wide enough (x 3) that the softmax is peaked.
    torch::manual_seed(7);
    for (const auto& [L, S, heads, d] :
         {std::tuple<int64_t, int64_t, int64_t, int64_t>{70, 66, 4, 64},
          {13, 31, 3, 9},
          {5, 7, 1, 4},
          {4, 1, 2, 6}}) {
        for (const auto dtype : {torch::kDouble, torch::kFloat}) {
            SCOPED_TRACE(std::to_string(L) + " x " + std::to_string(S) + ", heads " +
                         std::to_string(heads) + ", d " + std::to_string(d) +
                         (dtype == torch::kDouble ? ", double" : ", float"));
            const torch::Tensor q = torch::randn({L, d}, torch::kDouble).mul(3).to(dtype);
            const torch::Tensor k = torch::randn({S, d}, torch::kDouble).to(dtype);
            const torch::Tensor v = torch::randn({S, d}, torch::kDouble).to(dtype);
            const torch::Tensor want =
                Composed(q.to(torch::kDouble), k.to(torch::kDouble), v.to(torch::kDouble), heads);
            torch::Tensor got = torch::empty({L, d}, dtype);
            if (dtype == torch::kDouble) {
                AttentionRows(q.data_ptr<double>(), k.data_ptr<double>(), v.data_ptr<double>(), L,
                              S, heads, d, got.data_ptr<double>());
            } else {
                AttentionRows(q.data_ptr<float>(), k.data_ptr<float>(), v.data_ptr<float>(), L, S,
                              heads, d, got.data_ptr<float>());
            }
            const double tol = dtype == torch::kDouble ? 1e-12 : 1e-5;
            EXPECT_LT((got.to(torch::kDouble) - want).abs().max().item<double>(), tol);
        }
    }
}

}  // namespace
}  // namespace regbench::networks
