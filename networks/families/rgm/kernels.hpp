#pragma once
// RGM's N x M element-wise work at inference, fused into single passes over contiguous rows (no
// LibTorch: plain loops the compiler vectorises, as networks/families/rienet/matching.hpp).
// The LibTorch compositions in networks/families/rgm/net.cpp (training, autograd) compute the
// same values; these replace them when no gradient is recorded. At rgm-small's widths they were
// most of the forward's time (docs/performance.md, "RGM against its floor").
#include <cstdint>

namespace regbench::networks {

/// The authors' log-domain Sinkhorn with a slack row and column (SinkhornSlack in net.hpp) on one
/// batch item, `iterations` rounds, written as row and column potentials instead of updating the
/// padded matrix: with L the n x m log weights (row-major) and every slack entry 0,
///   a_i = -logsumexp( {L[i][j] + b_j : j < m} and 0 )   (the row step; the slack column's
///                                                         potential stays 0),
///   b_j = -logsumexp( {L[i][j] + a_i : i < n} and 0 )   (the column step; the slack row's
///                                                         stays 0),
/// starting from b = 0; on return L[i][j] is overwritten with exp(L[i][j] + a_i + b_j), the real
/// block of the Sinkhorn result, already exponentiated. The LibTorch version subtracts each
/// step's logsumexp from the padded matrix itself (the same values up to rounding: it adds the
/// 2 x iterations rounding errors of those subtractions, this one recomputes the sums from L).
/// `work` holds n + 3 m values. exp is FastExp (float, relative error < 3e-7; 0 below -87,
/// where the result is < 1.7e-38) or ExpClamped (double, < 1e-15).
void SinkhornSlackExp(float* L, int64_t n, int64_t m, int iterations, float* work);
void SinkhornSlackExp(double* L, int64_t n, int64_t m, int iterations, double* work);

/// Row softmax of scaled scores, in place: x[i][j] = exp(scale (x[i][j] - max_j x[i][j])) /
/// (sum over j of the same), for `n` rows of `m` (row-major, scale > 0), i.e. softmax(scale x,
/// -1). When `column_sums` is not null, each result is also added to column_sums[j] (the caller
/// zeroes them; RGM's adjacency normalises its columns by these sums).
void ScaledSoftmaxRows(float* x, int64_t n, int64_t m, double scale, float* column_sums);
void ScaledSoftmaxRows(double* x, int64_t n, int64_t m, double scale, double* column_sums);

/// x[i][j] /= max(column_sums[j], 1e-12) for n rows of m (F.normalize(p=1, dim=-2) of a
/// non-negative matrix, given its column sums).
void DivideColumns(float* x, int64_t n, int64_t m, const float* column_sums);
void DivideColumns(double* x, int64_t n, int64_t m, const double* column_sums);

/// The authors' LayerNorm on `n` rows of `d` (row-major), out = a (x - mean) / (std + eps) + b
/// with the unbiased standard deviation (two passes: the mean, then the squared deviations);
/// a and b hold d values. `out` may be `x`.
void LayerNormRows(const float* x, float* out, int64_t n, int64_t d, const float* a,
                   const float* b, double eps);
void LayerNormRows(const double* x, double* out, int64_t n, int64_t d, const double* a,
                   const double* b, double eps);

}  // namespace regbench::networks
