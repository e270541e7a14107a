#include "networks/families/regtr/kernels.hpp"

#include <algorithm>
#include <cmath>

namespace regbench::networks {
namespace {

template <typename T>
void NeighbourSums(const T* q, int64_t Q, const T* s, int64_t S, const int64_t* nb, int64_t H,
                   const T* kp, int64_t K, double extent, const T* x, int64_t C,
                   const bool* positive, T* out, T* count) {
    // The LibTorch composition divides by the extent as a scalar of the tensor's type.
    const T e = static_cast<T>(extent);
    std::fill(out, out + Q * K * C, T(0));
    for (int64_t i = 0; i < Q; ++i) {
        const T* qi = q + 3 * i;
        T* o = out + i * K * C;
        int64_t n = 0;
        for (int64_t h = 0; h < H; ++h) {
            const int64_t j = nb[i * H + h];
            if (j < 0 || j >= S) continue;  // the shadow point: weight 0, features 0
            if (positive[j]) ++n;
            const T* sj = s + 3 * j;
            const T* xj = x + j * C;
            const T dx = sj[0] - qi[0], dy = sj[1] - qi[1], dz = sj[2] - qi[2];
            for (int64_t k = 0; k < K; ++k) {
                const T a = dx - kp[3 * k], b = dy - kp[3 * k + 1], c = dz - kp[3 * k + 2];
                const T w = T(1) - std::sqrt(a * a + b * b + c * c) / e;
                if (!(w > T(0))) continue;
                T* ok = o + k * C;
                for (int64_t ch = 0; ch < C; ++ch) ok[ch] += w * xj[ch];
            }
        }
        count[i] = static_cast<T>(std::max<int64_t>(n, 1));
    }
}

}  // namespace

void KpconvNeighbourSums(const float* q, int64_t Q, const float* s, int64_t S, const int64_t* nb,
                         int64_t H, const float* kp, int64_t K, double extent, const float* x,
                         int64_t C, const bool* positive, float* out, float* count) {
    NeighbourSums(q, Q, s, S, nb, H, kp, K, extent, x, C, positive, out, count);
}

void KpconvNeighbourSums(const double* q, int64_t Q, const double* s, int64_t S, const int64_t* nb,
                         int64_t H, const double* kp, int64_t K, double extent, const double* x,
                         int64_t C, const bool* positive, double* out, double* count) {
    NeighbourSums(q, Q, s, S, nb, H, kp, K, extent, x, C, positive, out, count);
}

}  // namespace regbench::networks
