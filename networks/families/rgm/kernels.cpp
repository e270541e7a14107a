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

}  // namespace

REGBENCH_SIMD_CLONES void SinkhornSlackExp(float* L, int64_t n, int64_t m, int iterations,
                                           float* work) {
    Sinkhorn(L, n, m, iterations, work);
}

REGBENCH_SIMD_CLONES void SinkhornSlackExp(double* L, int64_t n, int64_t m, int iterations,
                                           double* work) {
    Sinkhorn(L, n, m, iterations, work);
}

REGBENCH_SIMD_CLONES void ScaledSoftmaxRows(float* x, int64_t n, int64_t m, double scale,
                                            float* column_sums) {
    SoftmaxRows(x, n, m, scale, column_sums);
}

REGBENCH_SIMD_CLONES void ScaledSoftmaxRows(double* x, int64_t n, int64_t m, double scale,
                                            double* column_sums) {
    SoftmaxRows(x, n, m, scale, column_sums);
}

REGBENCH_SIMD_CLONES void DivideColumns(float* x, int64_t n, int64_t m, const float* sums) {
    Columns(x, n, m, sums);
}

REGBENCH_SIMD_CLONES void DivideColumns(double* x, int64_t n, int64_t m, const double* sums) {
    Columns(x, n, m, sums);
}

}  // namespace regbench::networks
