#pragma once
// REGTR's element-wise work at inference as plain loops over contiguous rows (no LibTorch), as
// networks/families/rienet/matching.hpp and networks/families/rgm/kernels.hpp. The LibTorch
// compositions in networks/families/regtr/net.cpp (training, autograd) compute the same values;
// these replace them when no gradient is recorded. At regtr-small's widths the KPConv's
// per-point batched products were most of the forward's time (docs/performance.md, "REGTR
// against its floor").
#include <cstdint>

namespace regbench::networks {

/// The influence-weighted neighbour sums of a rigid KPConv (RegtrKpconvImpl::forward before its
/// kernel GEMM), for Q queries q (Q x 3), supports s (S x 3) with features x (S x C), the
/// neighbour indices nb (Q x H, S = the shadow point: no influence, zero features) and the K
/// kernel points kp (K x 3):
///   out[i][k][c] = sum over h of w(i, k, h) x[nb[i][h]][c],
///   w(i, k, h) = max(0, 1 - |s[nb[i][h]] - q[i] - kp[k]| / extent),
/// out row-major Q x K x C (overwritten), summed in neighbour order. count[i] (Q values) is the
/// number of the row's neighbours j with positive[j] != 0 (the caller's "features sum to more
/// than 0"; S values), at least 1.
void KpconvNeighbourSums(const float* q, int64_t Q, const float* s, int64_t S, const int64_t* nb,
                         int64_t H, const float* kp, int64_t K, double extent, const float* x,
                         int64_t C, const bool* positive, float* out, float* count);
void KpconvNeighbourSums(const double* q, int64_t Q, const double* s, int64_t S, const int64_t* nb,
                         int64_t H, const double* kp, int64_t K, double extent, const double* x,
                         int64_t C, const bool* positive, double* out, double* count);

}  // namespace regbench::networks
