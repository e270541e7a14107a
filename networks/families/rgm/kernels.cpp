#include "networks/families/rgm/kernels.hpp"

#include <algorithm>
#include <cmath>

#include "gmm/gauss_sum.hpp"
#include "gmm/simd_exp.hpp"
#include "networks/layers/row_reduce.hpp"

namespace regbench::networks {
namespace {

inline float Exp(float x) { return FastExp(x); }
inline double Exp(double x) { return ExpClamped(x); }

/// Sinkhorn by potentials (kernels.hpp). a: n row potentials, b: m column potentials, t: m
/// values of scratch (one row's shifted entries, then the column maxima), s: m column sums.
template <typename T>
__attribute__((always_inline)) inline void Sinkhorn(T* L, int64_t n, int64_t m, int iterations,
                                                    T* work) {
    T* a = work;
    T* b = a + n;
    T* t = b + m;
    T* s = t + m;
    for (int64_t j = 0; j < m; ++j) b[j] = 0;
    for (int it = 0; it < iterations; ++it) {
        // Row step: a_i = -logsumexp over the row's m entries L + b and its slack entry 0.
        for (int64_t i = 0; i < n; ++i) {
            const T* l = L + i * m;
            for (int64_t j = 0; j < m; ++j) t[j] = l[j] + b[j];
            const T top = std::max(T(0), RowMax(t, m));
            for (int64_t j = 0; j < m; ++j) t[j] = Exp(t[j] - top);
            a[i] = -(top + std::log(RowSum(t, m) + Exp(-top)));
        }
        // Column step: b_j = -logsumexp over the column's n entries L + a and its slack entry 0,
        // accumulated row by row (contiguous in j) into the column maxima t, then the sums s.
        for (int64_t j = 0; j < m; ++j) t[j] = 0;
        for (int64_t i = 0; i < n; ++i) {
            const T* l = L + i * m;
            const T ai = a[i];
            for (int64_t j = 0; j < m; ++j) t[j] = std::max(t[j], l[j] + ai);
        }
        for (int64_t j = 0; j < m; ++j) s[j] = Exp(-t[j]);
        for (int64_t i = 0; i < n; ++i) {
            const T* l = L + i * m;
            const T ai = a[i];
            for (int64_t j = 0; j < m; ++j) s[j] += Exp(l[j] + ai - t[j]);
        }
        for (int64_t j = 0; j < m; ++j) b[j] = -(t[j] + std::log(s[j]));
    }
    for (int64_t i = 0; i < n; ++i) {
        T* l = L + i * m;
        const T ai = a[i];
        for (int64_t j = 0; j < m; ++j) l[j] = Exp(l[j] + ai + b[j]);
    }
}

template <typename T>
__attribute__((always_inline)) inline void SoftmaxRows(T* x, int64_t n, int64_t m, double scale,
                                                       T* column_sums) {
    const T c = static_cast<T>(scale);
    for (int64_t i = 0; i < n; ++i) {
        T* r = x + i * m;
        const T top = RowMax(r, m);
        for (int64_t j = 0; j < m; ++j) r[j] = Exp(c * (r[j] - top));
        const T inv = T(1) / RowSum(r, m);
        for (int64_t j = 0; j < m; ++j) r[j] *= inv;
        if (column_sums != nullptr) {
            for (int64_t j = 0; j < m; ++j) column_sums[j] += r[j];
        }
    }
}

template <typename T>
__attribute__((always_inline)) inline void Columns(T* x, int64_t n, int64_t m, const T* sums) {
    for (int64_t i = 0; i < n; ++i) {
        T* r = x + i * m;
        for (int64_t j = 0; j < m; ++j) r[j] /= std::max(sums[j], T(1e-12));
    }
}

template <typename T>
__attribute__((always_inline)) inline void LayerNorm(const T* x, T* out, int64_t n, int64_t d,
                                                     const T* a, const T* b, double eps) {
    for (int64_t i = 0; i < n; ++i) {
        const T* r = x + i * d;
        T* o = out + i * d;
        const T mean = RowSum(r, d) / static_cast<T>(d);
        T dev[kReduceLanes] = {};
        int64_t j = 0;
        for (; j + kReduceLanes <= d; j += kReduceLanes) {
            for (int l = 0; l < kReduceLanes; ++l) dev[l] += (r[j + l] - mean) * (r[j + l] - mean);
        }
        for (; j < d; ++j) dev[0] += (r[j] - mean) * (r[j] - mean);
        T squares = 0;
        for (const T v : dev) squares += v;
        const T std = std::sqrt(squares / static_cast<T>(std::max<int64_t>(d - 1, 1)));
        const T inv = T(1) / (std + static_cast<T>(eps));
        for (j = 0; j < d; ++j) o[j] = a[j] * (r[j] - mean) * inv + b[j];
    }
}

}  // namespace

// Every kernel in float and in double, each compiled for every SIMD level.
#define REGBENCH_RGM_KERNELS(T)                                                                 \
    REGBENCH_SIMD_CLONES void SinkhornSlackExp(T* L, int64_t n, int64_t m, int iterations,      \
                                               T* work) {                                      \
        Sinkhorn(L, n, m, iterations, work);                                                   \
    }                                                                                          \
    REGBENCH_SIMD_CLONES void ScaledSoftmaxRows(T* x, int64_t n, int64_t m, double scale,      \
                                                T* column_sums) {                              \
        SoftmaxRows(x, n, m, scale, column_sums);                                              \
    }                                                                                          \
    REGBENCH_SIMD_CLONES void DivideColumns(T* x, int64_t n, int64_t m, const T* sums) {       \
        Columns(x, n, m, sums);                                                                \
    }                                                                                          \
    REGBENCH_SIMD_CLONES void LayerNormRows(const T* x, T* out, int64_t n, int64_t d,          \
                                            const T* a, const T* b, double eps) {              \
        LayerNorm(x, out, n, d, a, b, eps);                                                    \
    }

REGBENCH_RGM_KERNELS(float)
REGBENCH_RGM_KERNELS(double)
#undef REGBENCH_RGM_KERNELS

}  // namespace regbench::networks
