#include "networks/layers/attention_rows.hpp"

#include <algorithm>
#include <vector>

#include "gmm/gauss_sum.hpp"
#include "gmm/simd_exp.hpp"
#include "networks/layers/row_reduce.hpp"

namespace regbench::networks {
namespace {

inline float Exp(float x) { return FastExp(x); }
inline double Exp(double x) { return ExpClamped(x); }

template <typename T>
__attribute__((always_inline)) inline void Attention(const T* q, const T* k, const T* v, int64_t L,
                                                     int64_t S, int64_t heads, int64_t d, T* out) {
    const int64_t hd = d / heads;
    // One head's keys transposed (hd x S, each row contiguous in j) and one row's scores.
    std::vector<T> kt_buf(static_cast<size_t>(hd * S)), p_buf(static_cast<size_t>(S));
    T* kt = kt_buf.data();
    T* p = p_buf.data();
    for (int64_t h = 0; h < heads; ++h) {
        const int64_t off = h * hd;
        for (int64_t j = 0; j < S; ++j) {
            for (int64_t c = 0; c < hd; ++c) kt[c * S + j] = k[j * d + off + c];
        }
        for (int64_t i = 0; i < L; ++i) {
            const T* qi = q + i * d + off;
            // Scores: hd passes of a multiply-add over the row, which stays in L1.
            {
                const T q0 = qi[0];
                for (int64_t j = 0; j < S; ++j) p[j] = q0 * kt[j];
            }
            for (int64_t c = 1; c < hd; ++c) {
                const T qc = qi[c];
                const T* kc = kt + c * S;
                for (int64_t j = 0; j < S; ++j) p[j] += qc * kc[j];
            }
            const T top = RowMax(p, S);
            for (int64_t j = 0; j < S; ++j) p[j] = Exp(p[j] - top);
            const T inv = T(1) / RowSum(p, S);
            // Values: four rows of v a step into the row's hd outputs (in L1).
            T* o = out + i * d + off;
            for (int64_t c = 0; c < hd; ++c) o[c] = 0;
            int64_t j = 0;
            for (; j + 4 <= S; j += 4) {
                const T p0 = p[j], p1 = p[j + 1], p2 = p[j + 2], p3 = p[j + 3];
                const T* v0 = v + j * d + off;
                const T* v1 = v0 + d;
                const T* v2 = v1 + d;
                const T* v3 = v2 + d;
                for (int64_t c = 0; c < hd; ++c) {
                    o[c] += (p0 * v0[c] + p1 * v1[c]) + (p2 * v2[c] + p3 * v3[c]);
                }
            }
            for (; j < S; ++j) {
                const T pj = p[j];
                const T* vj = v + j * d + off;
                for (int64_t c = 0; c < hd; ++c) o[c] += pj * vj[c];
            }
            for (int64_t c = 0; c < hd; ++c) o[c] *= inv;
        }
    }
}

}  // namespace

REGBENCH_SIMD_CLONES void AttentionRows(const float* q, const float* k, const float* v, int64_t L,
                                        int64_t S, int64_t heads, int64_t d, float* out) {
    Attention(q, k, v, L, S, heads, d, out);
}

REGBENCH_SIMD_CLONES void AttentionRows(const double* q, const double* k, const double* v,
                                        int64_t L, int64_t S, int64_t heads, int64_t d,
                                        double* out) {
    Attention(q, k, v, L, S, heads, d, out);
}

}  // namespace regbench::networks
