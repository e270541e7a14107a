#pragma once
// RIENet's refined matching map at inference, fused into one pass over each row (no LibTorch:
// plain loops the compiler vectorises, as gmm/'s kernels). The LibTorch composition in
// networks/families/rienet/net.cpp (training, autograd) computes the same map in about ten passes
// over the N x M map and five temporaries; this one reads the distances and the row-side consensus
// sums once and writes the map over the distances.
#include <cstdint>

namespace regbench::networks {

/// The point-wise matching map of `n` rows: scores[i][j] = softmax over j of -dist[i][j]
/// (row-major n x m; exp as below).
void MatchingScoreRows(const float* dist, float* scores, int64_t n, int64_t m);
void MatchingScoreRows(const double* dist, double* scores, int64_t n, int64_t m);

/// For one batch item, row by row i < n (columns j < m):
///   nc[i][j]  = (sum over l = 1 .. k_nc - 1 of rows[i][idx_t[j * idx_stride + l]]) / (k_nc - 1)
///   map[i][j] = softmax over j of ( -exp(margin - nc[i][j]) * dist[i][j] ),
/// written into `dist` (row-major n x m). `rows` (n x m) holds each row's sums over the source
/// point's non-self neighbours of the point-wise matching map; idx_t (m x idx_stride) the target
/// points' neighbours, the point itself first. exp is FastExp (float, relative error < 3e-7) or
/// ExpClamped (double, < 1e-15).
void RefineMatchingRows(float* dist, const float* rows, const int64_t* idx_t, int64_t n, int64_t m,
                        int64_t idx_stride, int64_t k_nc, double margin);
void RefineMatchingRows(double* dist, const double* rows, const int64_t* idx_t, int64_t n,
                        int64_t m, int64_t idx_stride, int64_t k_nc, double margin);

}  // namespace regbench::networks
