#include "networks/layers/edge_stages.hpp"

#include <ATen/Parallel.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "gmm/simd_exp.hpp"  // REGBENCH_SIMD_CLONES

namespace regbench::networks {
namespace {

using torch::autograd::AutogradContext;
using torch::autograd::variable_list;

std::atomic<bool> g_fused_edge_stages{true};

// ---------------------------------------------------------------------------------------------
// Kernels. Plain loops over contiguous [M, C] maps (M = P k rows, k consecutive rows per point,
// the inner loop over the C contiguous channels, so compilers vectorise it). LibTorch 1.13 has no
// op that fuses BatchNorm's normalisation with ReLU and a max-with-argmax over k, nor a
// BatchNorm backward that takes the max's sparse gradient; its own CPU BatchNorm reduces an
// [M, C] map one channel at a time with a stride of C floats (a cache line per element), which
// is what made BatchNorm 22% of a training step. Sums are taken in the data type over one
// point's k rows, then added into double accumulators per point.
// ---------------------------------------------------------------------------------------------

#define REGBENCH_INLINE __attribute__((always_inline)) inline

// s1 += sum (y - shift), s2 += sum (y - shift)^2 over the rows of `points` points. The shift
// (the map's first row) keeps the variance free of the cancellation of E[y^2] - E[y]^2.
template <typename T>
REGBENCH_INLINE void ShiftedSumsBody(const T* __restrict y, int64_t points, int64_t k, int64_t C,
                                     const T* __restrict shift, T* __restrict f1, T* __restrict f2,
                                     double* __restrict s1, double* __restrict s2) {
    for (int64_t p = 0; p < points; ++p) {
        std::fill(f1, f1 + C, T(0));
        std::fill(f2, f2 + C, T(0));
        for (int64_t j = 0; j < k; ++j) {
            const T* __restrict row = y + (p * k + j) * C;
            for (int64_t c = 0; c < C; ++c) {
                const T d = row[c] - shift[c];
                f1[c] += d;
                f2[c] += d * d;
            }
        }
        for (int64_t c = 0; c < C; ++c) {
            s1[c] += f1[c];
            s2[c] += f2[c];
        }
    }
}

// z = ReLU(y alpha + beta) (written only with kRows), pooled = max over each point's k rows,
// arg = the row of the max within the point (first on ties).
template <typename T, bool kRows>
REGBENCH_INLINE void NormReluMaxBody(const T* __restrict y, int64_t points, int64_t k, int64_t C,
                                     const T* __restrict alpha, const T* __restrict beta,
                                     T* __restrict z, T* __restrict pooled, int64_t ld,
                                     int32_t* __restrict arg) {
    for (int64_t p = 0; p < points; ++p) {
        T* __restrict best = pooled + p * ld;
        int32_t* __restrict at = arg + p * C;
        for (int64_t j = 0; j < k; ++j) {
            const int64_t r = (p * k + j) * C;
            const T* __restrict row = y + r;
            const auto jj = static_cast<int32_t>(j);
            if (j == 0) {
                for (int64_t c = 0; c < C; ++c) {
                    const T v = row[c] * alpha[c] + beta[c];
                    const T t = v < T(0) ? T(0) : v;  // ReLU; NaN stays NaN as in torch::relu
                    if constexpr (kRows) z[r + c] = t;
                    best[c] = t;
                    at[c] = 0;
                }
            } else {
                for (int64_t c = 0; c < C; ++c) {
                    const T v = row[c] * alpha[c] + beta[c];
                    const T t = v < T(0) ? T(0) : v;
                    if constexpr (kRows) z[r + c] = t;
                    const bool greater = t > best[c];  // strict: ties keep the first row
                    best[c] = greater ? t : best[c];
                    at[c] = greater ? jj : at[c];
                }
            }
        }
    }
}

// Backward reduction of a stage whose rows feed the next stage: g = [z > 0] (dz + the pooled
// gradient at the argmax), written over dz for GradApplyRows; sum += g, dot += (y - mean) g.
template <typename T>
REGBENCH_INLINE void GradSumsRowsBody(T* __restrict dz, const T* __restrict z,
                                      const T* __restrict y, const T* __restrict mean,
                                      const int32_t* __restrict arg, const T* __restrict dpool,
                                      int64_t ld, int64_t points, int64_t k, int64_t C,
                                      T* __restrict f1, T* __restrict f2, double* __restrict sum,
                                      double* __restrict dot) {
    for (int64_t p = 0; p < points; ++p) {
        std::fill(f1, f1 + C, T(0));
        std::fill(f2, f2 + C, T(0));
        const int32_t* __restrict at = arg + p * C;
        const T* __restrict dp = dpool + p * ld;
        for (int64_t j = 0; j < k; ++j) {
            const int64_t r = (p * k + j) * C;
            const auto jj = static_cast<int32_t>(j);
            for (int64_t c = 0; c < C; ++c) {
                const T g0 = dz[r + c] + (at[c] == jj ? dp[c] : T(0));
                const T g = z[r + c] <= T(0) ? T(0) : g0;  // threshold_backward's rule
                dz[r + c] = g;
                f1[c] += g;
                f2[c] += (y[r + c] - mean[c]) * g;
            }
        }
        for (int64_t c = 0; c < C; ++c) {
            sum[c] += f1[c];
            dot[c] += f2[c];
        }
    }
}

// The same for the last stage, whose only gradient is the pooled one: g is non-zero only at the
// argmax, where z is the pooled value.
template <typename T>
REGBENCH_INLINE void GradSumsPooledBody(const T* __restrict y, const T* __restrict mean,
                                        const int32_t* __restrict arg, const T* __restrict dpool,
                                        const T* __restrict pooled, int64_t ld, int64_t points,
                                        int64_t k, int64_t C, double* __restrict sum,
                                        double* __restrict dot) {
    for (int64_t p = 0; p < points; ++p) {
        const int32_t* __restrict at = arg + p * C;
        const T* __restrict dp = dpool + p * ld;
        const T* __restrict pv = pooled + p * ld;
        for (int64_t c = 0; c < C; ++c) {
            const T g = pv[c] <= T(0) ? T(0) : dp[c];
            sum[c] += g;
            dot[c] += (y[(p * k + at[c]) * C + c] - mean[c]) * g;
        }
    }
}

// BatchNorm's input gradient, in place over the g that GradSumsRows left in dz:
// dx = (g - grad_mean - (y - mean) kk) invstd w, the expression of LibTorch's
// batch_norm_cpu_backward (kk = dot invstd^2 / M).
template <typename T>
REGBENCH_INLINE void GradApplyRowsBody(T* __restrict io, const T* __restrict y,
                                       const T* __restrict mean, int64_t rows, int64_t C,
                                       const T* __restrict grad_mean, const T* __restrict kk,
                                       const T* __restrict invstd, const T* __restrict w) {
    for (int64_t r = 0; r < rows * C; r += C) {
        for (int64_t c = 0; c < C; ++c) {
            const T centred = (y[r + c] - mean[c]) * kk[c];
            io[r + c] = (io[r + c] - grad_mean[c] - centred) * invstd[c] * w[c];
        }
    }
}

// The last stage's input gradient, in place over y (which it reads first).
template <typename T>
REGBENCH_INLINE void GradApplyPooledBody(T* __restrict io, const T* __restrict mean,
                                         const int32_t* __restrict arg, const T* __restrict dpool,
                                         const T* __restrict pooled, int64_t ld, int64_t points,
                                         int64_t k, int64_t C, const T* __restrict grad_mean,
                                         const T* __restrict kk, const T* __restrict invstd,
                                         const T* __restrict w) {
    for (int64_t p = 0; p < points; ++p) {
        const int32_t* __restrict at = arg + p * C;
        const T* __restrict dp = dpool + p * ld;
        const T* __restrict pv = pooled + p * ld;
        for (int64_t j = 0; j < k; ++j) {
            const int64_t r = (p * k + j) * C;
            const auto jj = static_cast<int32_t>(j);
            for (int64_t c = 0; c < C; ++c) {
                const bool flows = at[c] == jj && !(pv[c] <= T(0));
                const T g = flows ? dp[c] : T(0);
                const T centred = (io[r + c] - mean[c]) * kk[c];
                io[r + c] = (g - grad_mean[c] - centred) * invstd[c] * w[c];
            }
        }
    }
}

// One entry point per kernel and type, compiled for AVX-512, AVX2 and the baseline.
#define REGBENCH_EDGE_KERNELS(T)                                                                  \
    REGBENCH_SIMD_CLONES void ShiftedSums(const T* y, int64_t points, int64_t k, int64_t C,       \
                                          const T* shift, T* f1, T* f2, double* s1, double* s2) { \
        ShiftedSumsBody<T>(y, points, k, C, shift, f1, f2, s1, s2);                               \
    }                                                                                             \
    REGBENCH_SIMD_CLONES void NormReluMax(const T* y, int64_t points, int64_t k, int64_t C,       \
                                          const T* alpha, const T* beta, T* z, T* pooled,         \
                                          int64_t ld, int32_t* arg) {                             \
        if (z != nullptr) {                                                                       \
            NormReluMaxBody<T, true>(y, points, k, C, alpha, beta, z, pooled, ld, arg);           \
        } else {                                                                                  \
            NormReluMaxBody<T, false>(y, points, k, C, alpha, beta, z, pooled, ld, arg);          \
        }                                                                                         \
    }                                                                                             \
    REGBENCH_SIMD_CLONES void GradSumsRows(T* dz, const T* z, const T* y, const T* mean,          \
                                           const int32_t* arg, const T* dpool, int64_t ld,        \
                                           int64_t points, int64_t k, int64_t C, T* f1, T* f2,    \
                                           double* sum, double* dot) {                            \
        GradSumsRowsBody<T>(dz, z, y, mean, arg, dpool, ld, points, k, C, f1, f2, sum, dot);      \
    }                                                                                             \
    REGBENCH_SIMD_CLONES void GradSumsPooled(                                                     \
        const T* y, const T* mean, const int32_t* arg, const T* dpool, const T* pooled,           \
        int64_t ld, int64_t points, int64_t k, int64_t C, double* sum, double* dot) {             \
        GradSumsPooledBody<T>(y, mean, arg, dpool, pooled, ld, points, k, C, sum, dot);           \
    }                                                                                             \
    REGBENCH_SIMD_CLONES void GradApplyRows(T* io, const T* y, const T* mean, int64_t rows,       \
                                            int64_t C, const T* grad_mean, const T* kk,           \
                                            const T* invstd, const T* w) {                        \
        GradApplyRowsBody<T>(io, y, mean, rows, C, grad_mean, kk, invstd, w);                     \
    }                                                                                             \
    REGBENCH_SIMD_CLONES void GradApplyPooled(                                                    \
        T* io, const T* mean, const int32_t* arg, const T* dpool, const T* pooled, int64_t ld,    \
        int64_t points, int64_t k, int64_t C, const T* grad_mean, const T* kk, const T* invstd,   \
        const T* w) {                                                                             \
        GradApplyPooledBody<T>(io, mean, arg, dpool, pooled, ld, points, k, C, grad_mean, kk,     \
                               invstd, w);                                                        \
    }

REGBENCH_EDGE_KERNELS(float)
REGBENCH_EDGE_KERNELS(double)
#undef REGBENCH_EDGE_KERNELS

// Work is split into fixed chunks of points, run on LibTorch's intra-op threads. The chunks do
// not depend on the thread count, and per-chunk sums are added in chunk order, so results do not
// either.
constexpr int64_t kChunkPoints = 128;

int64_t ChunkCount(int64_t points) { return (points + kChunkPoints - 1) / kChunkPoints; }

template <typename Body>
void ForChunks(int64_t points, const Body& body) {
    at::parallel_for(0, ChunkCount(points), 1, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) {
            const int64_t first = i * kChunkPoints;
            body(i, first, std::min(points, first + kChunkPoints) - first);
        }
    });
}

// Per-chunk partial sums [chunks, 2, C] (double) added in chunk order into two C-vectors.
std::pair<std::vector<double>, std::vector<double>> AddChunks(const std::vector<double>& parts,
                                                              int64_t chunks, int64_t C) {
    std::vector<double> a(static_cast<size_t>(C), 0.0), b(static_cast<size_t>(C), 0.0);
    for (int64_t i = 0; i < chunks; ++i) {
        const double* pa = parts.data() + i * 2 * C;
        for (int64_t c = 0; c < C; ++c) {
            a[static_cast<size_t>(c)] += pa[c];
            b[static_cast<size_t>(c)] += pa[C + c];
        }
    }
    return {std::move(a), std::move(b)};
}

// ---------------------------------------------------------------------------------------------
// The autograd Function over the whole chain. Inputs (all tensors, in this order): rows, then per
// stage the weight [C_out, C_in], BatchNorm's weight and bias. Running statistics are updated in
// the forward from `stages` (not autograd inputs).
// ---------------------------------------------------------------------------------------------

// Forward and Backward are long on purpose: each is one loop over the stages (Backward in
// reverse) whose steps hand tensors to each other and to the saved context in LibTorch's
// autograd order; the arithmetic itself is in the kernels above.
struct EdgeChainFunction : public torch::autograd::Function<EdgeChainFunction> {
    template <typename T>
    static torch::Tensor Forward(AutogradContext* ctx, const torch::Tensor& rows,
                                 const std::vector<EdgeStage>& stages, int64_t k) {
        const int64_t M = rows.size(0), P = M / k;
        int64_t total = 0;
        for (const EdgeStage& s : stages) total += s.weight.size(0);
        torch::Tensor out = torch::empty({P, total}, rows.options());
        std::vector<torch::Tensor> ys, zs, args, means, invstds;
        torch::Tensor x = rows;
        int64_t offset = 0;
        const int64_t chunks = ChunkCount(P);
        for (size_t s = 0; s < stages.size(); ++s) {
            const EdgeStage& st = stages[s];
            const int64_t C = st.weight.size(0);
            const bool rows_out = s + 1 < stages.size();
            const torch::Tensor y = torch::mm(x, st.weight.t());  // [M, C], contiguous
            const T* yp = y.data_ptr<T>();
            // Batch statistics over the M rows, as BatchNorm2d takes them over (B, N, k).
            std::vector<double> parts(static_cast<size_t>(chunks * 2 * C), 0.0);
            ForChunks(P, [&](int64_t chunk, int64_t first, int64_t count) {
                std::vector<T> f(static_cast<size_t>(2 * C));
                double* part = parts.data() + chunk * 2 * C;
                ShiftedSums(yp + first * k * C, count, k, C, yp, f.data(), f.data() + C, part,
                            part + C);
            });
            const auto [s1, s2] = AddChunks(parts, chunks, C);
            torch::Tensor mean = torch::empty({C}, rows.options());
            torch::Tensor invstd = torch::empty({C}, rows.options());
            torch::Tensor alpha = torch::empty({C}, rows.options());
            torch::Tensor beta = torch::empty({C}, rows.options());
            {
                const torch::Tensor w = st.bn_weight.contiguous(), b = st.bn_bias.contiguous();
                auto rm = st.running_mean.accessor<T, 1>();
                auto rv = st.running_var.accessor<T, 1>();
                const double n = static_cast<double>(M);
                for (int64_t c = 0; c < C; ++c) {
                    const double shift = static_cast<double>(yp[c]);
                    const double m1 = s1[static_cast<size_t>(c)] / n;
                    const double mean_c = shift + m1;
                    const double var_sum = std::max(0.0, s2[static_cast<size_t>(c)] - n * m1 * m1);
                    const T mean_t = static_cast<T>(mean_c);
                    const T inv = static_cast<T>(1.0 / std::sqrt(var_sum / n + st.eps));
                    mean.data_ptr<T>()[c] = mean_t;
                    invstd.data_ptr<T>()[c] = inv;
                    // As batch_norm_cpu_update_stats_template: momentum-weighted, var unbiased.
                    rm[c] = static_cast<T>(st.momentum * static_cast<double>(mean_t) +
                                           (1 - st.momentum) * static_cast<double>(rm[c]));
                    rv[c] = static_cast<T>(st.momentum * (var_sum / (n - 1)) +
                                           (1 - st.momentum) * static_cast<double>(rv[c]));
                    // As batch_norm_cpu_collect_linear_and_constant_terms.
                    const T wc = w.data_ptr<T>()[c], bc = b.data_ptr<T>()[c];
                    alpha.data_ptr<T>()[c] = inv * wc;
                    beta.data_ptr<T>()[c] = bc - mean_t * inv * wc;
                }
                st.num_batches_tracked.add_(1);
            }
            torch::Tensor z = rows_out ? torch::empty({M, C}, rows.options()) : torch::Tensor();
            torch::Tensor arg = torch::empty({P, C}, rows.options().dtype(torch::kInt));
            T* zp = rows_out ? z.data_ptr<T>() : nullptr;
            T* op = out.data_ptr<T>() + offset;
            int32_t* ap = arg.data_ptr<int32_t>();
            const T* al = alpha.data_ptr<T>();
            const T* be = beta.data_ptr<T>();
            ForChunks(P, [&](int64_t, int64_t first, int64_t count) {
                NormReluMax(yp + first * k * C, count, k, C, al, be,
                            zp != nullptr ? zp + first * k * C : nullptr, op + first * total, total,
                            ap + first * C);
            });
            ys.push_back(y);
            zs.push_back(z);
            args.push_back(arg);
            means.push_back(mean);
            invstds.push_back(invstd);
            x = z;
            offset += C;
        }
        ctx->saved_data["k"] = k;
        ctx->saved_data["y"] = ys;
        ctx->saved_data["arg"] = args;
        ctx->saved_data["mean"] = means;
        ctx->saved_data["invstd"] = invstds;
        // z of every stage but the last (undefined); kept as a list without that entry.
        zs.pop_back();
        ctx->saved_data["z"] = zs;
        return out;
    }

    static torch::Tensor forward(AutogradContext* ctx, at::TensorList inputs,
                                 const std::vector<EdgeStage>* stages, int64_t k) {
        const torch::Tensor rows = inputs[0].contiguous();
        std::vector<EdgeStage> contiguous = *stages;
        for (EdgeStage& s : contiguous) s.weight = s.weight.contiguous();
        torch::Tensor out = rows.scalar_type() == torch::kDouble
                                ? Forward<double>(ctx, rows, contiguous, k)
                                : Forward<float>(ctx, rows, contiguous, k);
        variable_list saved(inputs.begin(), inputs.end());
        saved.push_back(out);
        ctx->save_for_backward(saved);
        return out;
    }

    // Long on purpose, as Forward (the comment above this struct).
    template <typename T>
    static variable_list Backward(AutogradContext* ctx, const torch::Tensor& dout) {
        const variable_list saved = ctx->get_saved_variables();
        const auto n_stages = static_cast<int64_t>((saved.size() - 2) / 3);
        const int64_t k = ctx->saved_data["k"].toInt();
        std::vector<torch::Tensor> ys = ctx->saved_data["y"].toTensorVector();
        std::vector<torch::Tensor> zs = ctx->saved_data["z"].toTensorVector();
        const std::vector<torch::Tensor> args = ctx->saved_data["arg"].toTensorVector();
        const std::vector<torch::Tensor> means = ctx->saved_data["mean"].toTensorVector();
        const std::vector<torch::Tensor> invstds = ctx->saved_data["invstd"].toTensorVector();
        ctx->saved_data.clear();  // so that the maps below are freed as soon as they are used
        const torch::Tensor& rows = saved[0];
        const torch::Tensor& out = saved.back();
        const int64_t M = rows.size(0), P = M / k, total = out.size(1);
        const int64_t chunks = ChunkCount(P);
        const T* dp_all = dout.data_ptr<T>();
        const T* pooled_all = out.data_ptr<T>();
        // One gradient per Function input: rows, 3 per stage, then the two non-tensor arguments.
        variable_list grads(static_cast<size_t>(1 + 3 * n_stages + 2));
        int64_t offset = total;
        torch::Tensor dz;  // gradient w.r.t. this stage's rows, from the next stage's GEMM
        for (int64_t s = n_stages - 1; s >= 0; --s) {
            const auto su = static_cast<size_t>(s);
            const torch::Tensor& weight = saved[static_cast<size_t>(1 + 3 * s)];
            const torch::Tensor gamma = saved[static_cast<size_t>(2 + 3 * s)].contiguous();
            const int64_t C = weight.size(0);
            offset -= C;
            const bool rows_out = s + 1 < n_stages;
            const T* yp = ys[su].data_ptr<T>();
            const T* mp = means[su].data_ptr<T>();
            const T* ip = invstds[su].data_ptr<T>();
            const int32_t* ap = args[su].data_ptr<int32_t>();
            const T* dp = dp_all + offset;
            const T* pp = pooled_all + offset;
            const T* zp = rows_out ? zs[su].data_ptr<T>() : nullptr;
            T* dzp = rows_out ? dz.data_ptr<T>() : nullptr;
            std::vector<double> parts(static_cast<size_t>(chunks * 2 * C), 0.0);
            ForChunks(P, [&](int64_t chunk, int64_t first, int64_t count) {
                double* part = parts.data() + chunk * 2 * C;
                if (rows_out) {
                    std::vector<T> f(static_cast<size_t>(2 * C));
                    GradSumsRows(dzp + first * k * C, zp + first * k * C, yp + first * k * C, mp,
                                 ap + first * C, dp + first * total, total, count, k, C, f.data(),
                                 f.data() + C, part, part + C);
                } else {
                    GradSumsPooled(yp + first * k * C, mp, ap + first * C, dp + first * total,
                                   pp + first * total, total, count, k, C, part, part + C);
                }
            });
            const auto [sum, dot] = AddChunks(parts, chunks, C);
            // As batch_norm_cpu_backward: grad_mean = sum / M, kk = dot invstd^2 / M,
            // grad weight = dot invstd, grad bias = sum.
            torch::Tensor grad_mean = torch::empty({C}, rows.options());
            torch::Tensor kk = torch::empty({C}, rows.options());
            torch::Tensor grad_gamma = torch::empty({C}, rows.options());
            torch::Tensor grad_beta = torch::empty({C}, rows.options());
            for (int64_t c = 0; c < C; ++c) {
                const auto cu = static_cast<size_t>(c);
                grad_mean.data_ptr<T>()[c] = static_cast<T>(sum[cu] / static_cast<double>(M));
                kk.data_ptr<T>()[c] = static_cast<T>(dot[cu]) * ip[c] * ip[c] / static_cast<T>(M);
                grad_gamma.data_ptr<T>()[c] = static_cast<T>(dot[cu] * static_cast<double>(ip[c]));
                grad_beta.data_ptr<T>()[c] = static_cast<T>(sum[cu]);
            }
            // The gradient w.r.t. the GEMM's output, in place over dz (rows) or over y (last).
            torch::Tensor dy = rows_out ? dz : ys[su];
            T* io = dy.data_ptr<T>();
            const T* gm = grad_mean.data_ptr<T>();
            const T* kp = kk.data_ptr<T>();
            const T* wp = gamma.data_ptr<T>();
            ForChunks(P, [&](int64_t, int64_t first, int64_t count) {
                if (rows_out) {
                    GradApplyRows(io + first * k * C, yp + first * k * C, mp, count * k, C, gm, kp,
                                  ip, wp);
                } else {
                    GradApplyPooled(io + first * k * C, mp, ap + first * C, dp + first * total,
                                    pp + first * total, total, count, k, C, gm, kp, ip, wp);
                }
            });
            ys[su].reset();
            if (rows_out) zs[su].reset();
            dz.reset();
            const torch::Tensor& input = s == 0 ? rows : zs[su - 1];
            if (ctx->needs_input_grad(static_cast<size_t>(1 + 3 * s))) {
                grads[static_cast<size_t>(1 + 3 * s)] = torch::mm(dy.t(), input);
            }
            grads[static_cast<size_t>(2 + 3 * s)] = grad_gamma;
            grads[static_cast<size_t>(3 + 3 * s)] = grad_beta;
            if (s > 0 || ctx->needs_input_grad(0)) {
                torch::Tensor dx = torch::mm(dy, weight);
                if (s > 0) {
                    dz = dx;
                } else {
                    grads[0] = dx;
                }
            }
        }
        return grads;
    }

    static variable_list backward(AutogradContext* ctx, variable_list grad_outputs) {
        const torch::Tensor dout = grad_outputs[0];
        if (!dout.defined()) {
            const size_t n = ctx->get_saved_variables().size();  // rows, 3 per stage, out
            return variable_list(n - 2 + 1 + 2);
        }
        return dout.scalar_type() == torch::kDouble ? Backward<double>(ctx, dout.contiguous())
                                                    : Backward<float>(ctx, dout.contiguous());
    }
};

}  // namespace

EdgeStage EdgeStageOf(const torch::nn::Conv2d& conv, const torch::nn::BatchNorm2d& bn) {
    EdgeStage s;
    s.weight = conv->weight.view({conv->weight.size(0), conv->weight.size(1)});
    s.bn_weight = bn->weight;
    s.bn_bias = bn->bias;
    s.running_mean = bn->running_mean;
    s.running_var = bn->running_var;
    s.num_batches_tracked = bn->num_batches_tracked;
    const auto& o = bn->options;
    s.momentum = o.momentum().has_value() ? o.momentum().value() : 0.1;
    s.eps = o.eps();
    return s;
}

torch::Tensor EdgeStagesReference(const torch::Tensor& rows, const std::vector<EdgeStage>& stages,
                                  int64_t k) {
    const int64_t points = rows.size(0) / k;
    torch::Tensor x = rows;
    std::vector<torch::Tensor> pooled;
    for (const EdgeStage& s : stages) {
        {
            torch::NoGradGuard no_grad;
            s.num_batches_tracked.add_(1);  // as BatchNorm2d::forward counts its batches
        }
        // In place: BatchNorm's backward needs its input and batch statistics, not its output.
        x = torch::batch_norm(torch::mm(x, s.weight.t()), s.bn_weight, s.bn_bias, s.running_mean,
                              s.running_var, /*training=*/true, s.momentum, s.eps,
                              /*cudnn_enabled=*/false)
                .relu_();
        // max with indices: its backward scatters to the argmax (amax's builds an equality mask).
        pooled.push_back(std::get<0>(x.view({points, k, x.size(1)}).max(1)));
    }
    return torch::cat(pooled, 1);
}

torch::Tensor EdgeStagesFused(const torch::Tensor& rows, const std::vector<EdgeStage>& stages,
                              int64_t k) {
    if (stages.empty()) throw std::invalid_argument("EdgeStagesFused: no stages");
    if (rows.dim() != 2 || k < 1 || rows.size(0) % k != 0 || rows.size(0) == 0) {
        throw std::invalid_argument("EdgeStagesFused: rows must be [P k, C] with P >= 1");
    }
    if (!rows.device().is_cpu() ||
        (rows.scalar_type() != torch::kFloat && rows.scalar_type() != torch::kDouble)) {
        throw std::invalid_argument("EdgeStagesFused: CPU float or double rows only");
    }
    if (k > std::numeric_limits<int32_t>::max()) {
        throw std::invalid_argument("EdgeStagesFused: k too large");
    }
    variable_list inputs{rows};
    int64_t channels = rows.size(1);
    for (const EdgeStage& s : stages) {
        if (s.weight.dim() != 2 || s.weight.size(1) != channels ||
            s.weight.scalar_type() != rows.scalar_type() ||
            s.running_mean.scalar_type() != rows.scalar_type()) {
            throw std::invalid_argument("EdgeStagesFused: stage shapes or types do not chain");
        }
        channels = s.weight.size(0);
        inputs.push_back(s.weight);
        inputs.push_back(s.bn_weight);
        inputs.push_back(s.bn_bias);
    }
    return EdgeChainFunction::apply(at::TensorList(inputs), &stages, k);
}

void SetFusedEdgeStages(bool enabled) { g_fused_edge_stages.store(enabled); }
bool FusedEdgeStages() { return g_fused_edge_stages.load(); }

}  // namespace regbench::networks
