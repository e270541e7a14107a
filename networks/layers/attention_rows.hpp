#pragma once
// Multi-head scaled dot-product attention at inference, one query row at a time (no LibTorch:
// plain loops the compiler vectorises, compiled for AVX-512, AVX2 and the baseline as gmm/'s
// kernels). LibTorch's composition (bmm, softmax, bmm) writes and re-reads each head's L x S
// score map three times and runs the products with a head width of d / heads as the inner
// dimension (16 at regtr-small's widths), where BLAS spends as long packing and zeroing as
// multiplying; here each row's S scores stay in L1. Used by REGTR's attention when no gradient
// is recorded (networks/families/regtr/net.cpp); with autograd it runs the LibTorch composition.
// RGM's attention has the same form but keeps its own (docs/performance.md, "RGM against its
// floor": the rounding change moved 3 of 20 shipped-checkpoint transforms by up to 0.16 deg).
#include <cstdint>

namespace regbench::networks {

/// For each head h < heads and query row i < L (hd = d / heads columns a head, d = heads hd):
///   p[j]          = softmax over j < S of  sum over c < hd of q[i][h hd + c] k[j][h hd + c],
///   out[i][h hd + c] = sum over j of p[j] v[j][h hd + c],
/// q (L x d), k and v (S x d), out (L x d), all row-major; q carries the 1 / sqrt(hd) scale
/// already. exp is FastExp (float, relative error < 3e-7) or ExpClamped (double, < 1e-15);
/// sums in row order, so results equal LibTorch's up to rounding.
void AttentionRows(const float* q, const float* k, const float* v, int64_t L, int64_t S,
                   int64_t heads, int64_t d, float* out);
void AttentionRows(const double* q, const double* k, const double* v, int64_t L, int64_t S,
                   int64_t heads, int64_t d, double* out);

}  // namespace regbench::networks
