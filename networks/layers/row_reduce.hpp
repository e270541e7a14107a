#pragma once
// Reductions over a contiguous row for the fused element-wise kernels (RIENet's matching, RGM's
// Sinkhorn and softmaxes), with eight explicit partial results that the compiler maps onto
// vector lanes: a plain `acc += x[j]` loop stays scalar without -ffast-math (it may not
// reassociate), and at m = 717 that scalar chain cost as much as an exp pass. No LibTorch.
#include <cstdint>
#include <limits>

namespace regbench::networks {

inline constexpr int kReduceLanes = 8;

template <typename T, typename Op>
__attribute__((always_inline)) inline T Reduce(const T* x, int64_t m, T init, Op op) {
    T acc[kReduceLanes];
    for (T& a : acc) a = init;
    int64_t j = 0;
    for (; j + kReduceLanes <= m; j += kReduceLanes) {
        for (int l = 0; l < kReduceLanes; ++l) acc[l] = op(acc[l], x[j + l]);
    }
    for (; j < m; ++j) acc[0] = op(acc[0], x[j]);
    T r = acc[0];
    for (int l = 1; l < kReduceLanes; ++l) r = op(r, acc[l]);
    return r;
}

template <typename T>
__attribute__((always_inline)) inline T RowMin(const T* x, int64_t m) {
    return Reduce(x, m, std::numeric_limits<T>::infinity(),
                  [](T a, T b) { return b < a ? b : a; });
}

template <typename T>
__attribute__((always_inline)) inline T RowMax(const T* x, int64_t m) {
    return Reduce(x, m, -std::numeric_limits<T>::infinity(),
                  [](T a, T b) { return b > a ? b : a; });
}

template <typename T>
__attribute__((always_inline)) inline T RowSum(const T* x, int64_t m) {
    return Reduce(x, m, T(0), [](T a, T b) { return a + b; });
}

}  // namespace regbench::networks
