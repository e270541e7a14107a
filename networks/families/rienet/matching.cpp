#include "networks/families/rienet/matching.hpp"

#include <algorithm>
#include <vector>

#include "gmm/gauss_sum.hpp"
#include "gmm/simd_exp.hpp"
#include "networks/layers/row_reduce.hpp"

namespace regbench::networks {
namespace {

inline float Exp(float x) { return FastExp(x); }
inline double Exp(double x) { return ExpClamped(x); }

/// x[j] = exp(x[j] - top) / sum over j of the same, in place.
template <typename T>
__attribute__((always_inline)) inline void SoftmaxInPlace(T* x, int64_t m, T top) {
    for (int64_t j = 0; j < m; ++j) x[j] = Exp(x[j] - top);
    const T inv = T(1) / RowSum(x, m);
    for (int64_t j = 0; j < m; ++j) x[j] *= inv;
}

template <typename T>
__attribute__((always_inline)) inline void RefineRows(T* dist, const T* rows,
                                                      const int64_t* idx_t, int64_t n, int64_t m,
                                                      int64_t idx_stride, int64_t k_nc,
                                                      double margin) {
    std::vector<T> buf(static_cast<size_t>(m));
    T* b = buf.data();
    const T scale = T(1) / static_cast<T>(k_nc - 1);
    const T mg = static_cast<T>(margin);
    for (int64_t i = 0; i < n; ++i) {
        const T* r = rows + i * m;
        T* d = dist + i * m;
        // Column-side consensus: a gather within one row (m values, in cache).
        for (int64_t j = 0; j < m; ++j) {
            const int64_t* nb = idx_t + j * idx_stride;
            T s = 0;
            for (int64_t l = 1; l < k_nc; ++l) s += r[nb[l]];
            b[j] = mg - s * scale;
        }
        // Logits -exp(margin - nc) d, stored negated (>= 0) so their minimum is the max logit.
        for (int64_t j = 0; j < m; ++j) b[j] = Exp(b[j]) * d[j];
        const T low = RowMin(b, m);
        for (int64_t j = 0; j < m; ++j) d[j] = low - b[j];
        SoftmaxInPlace(d, m, T(0));
    }
}

template <typename T>
__attribute__((always_inline)) inline void ScoreRows(const T* dist, T* scores, int64_t n,
                                                     int64_t m) {
    for (int64_t i = 0; i < n; ++i) {
        const T* d = dist + i * m;
        T* s = scores + i * m;
        const T low = RowMin(d, m);
        for (int64_t j = 0; j < m; ++j) s[j] = low - d[j];
        SoftmaxInPlace(s, m, T(0));
    }
}

}  // namespace

REGBENCH_SIMD_CLONES void MatchingScoreRows(const float* dist, float* scores, int64_t n,
                                            int64_t m) {
    ScoreRows(dist, scores, n, m);
}

REGBENCH_SIMD_CLONES void MatchingScoreRows(const double* dist, double* scores, int64_t n,
                                            int64_t m) {
    ScoreRows(dist, scores, n, m);
}

REGBENCH_SIMD_CLONES void RefineMatchingRows(float* dist, const float* rows, const int64_t* idx_t,
                                             int64_t n, int64_t m, int64_t idx_stride,
                                             int64_t k_nc, double margin) {
    RefineRows(dist, rows, idx_t, n, m, idx_stride, k_nc, margin);
}

REGBENCH_SIMD_CLONES void RefineMatchingRows(double* dist, const double* rows,
                                             const int64_t* idx_t, int64_t n, int64_t m,
                                             int64_t idx_stride, int64_t k_nc, double margin) {
    RefineRows(dist, rows, idx_t, n, m, idx_stride, k_nc, margin);
}

}  // namespace regbench::networks
