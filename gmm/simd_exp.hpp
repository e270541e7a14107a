#pragma once
// Branch-free double-precision exp that compilers vectorise inside `#pragma omp simd` loops
// (libm's exp is a scalar call). Dense Gaussian sums are exp-bound.
#include <cstdint>
#include <cstring>

/// Compiles a hot kernel for x86-64-v4 (AVX-512), v3 (AVX2+FMA) and the baseline, picked at
/// load time (GCC function multiversioning). Results may differ in the last bits between
/// clones (FMA contraction), never between runs or thread counts on one machine.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define REGBENCH_SIMD_CLONES \
    __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define REGBENCH_SIMD_CLONES
#endif

namespace regbench {

/// exp(x) for x <= 709, relative error below 1e-15; returns exactly 0 for x < -708.39
/// (where libm's result is subnormal or 0). Cody-Waite reduction x = n ln2 + r, |r| <= ln2/2,
/// degree-13 Taylor polynomial (truncation < 5e-18), scaling by 2^n through the exponent bits.
__attribute__((always_inline)) inline double ExpClamped(double x) {
    constexpr double kLog2e = 1.4426950408889634074;
    constexpr double kLn2Hi = 6.93147180369123816490e-01;
    constexpr double kLn2Lo = 1.90821492927058770002e-10;
    constexpr double kShift = 6755399441055744.0;  // 1.5 * 2^52: rounds to nearest integer
    constexpr double kMin = -708.39;
    const double keep = x < kMin ? 0.0 : 1.0;  // selects, not branches
    x = x < kMin ? kMin : x;
    const double kd = x * kLog2e + kShift;
    const double n = kd - kShift;
    const double r = (x - n * kLn2Hi) - n * kLn2Lo;
    double p = 1.0 / 6227020800.0;  // 1/13!
    p = p * r + 1.0 / 479001600.0;
    p = p * r + 1.0 / 39916800.0;
    p = p * r + 1.0 / 3628800.0;
    p = p * r + 1.0 / 362880.0;
    p = p * r + 1.0 / 40320.0;
    p = p * r + 1.0 / 5040.0;
    p = p * r + 1.0 / 720.0;
    p = p * r + 1.0 / 120.0;
    p = p * r + 1.0 / 24.0;
    p = p * r + 1.0 / 6.0;
    p = p * r + 0.5;
    p = p * r + 1.0;
    p = p * r + 1.0;
    // The low mantissa bits of kd hold n (two's complement): 2^n = ((bits + 1023) << 52).
    union {
        double d;
        std::uint64_t u;
    } bits{kd};
    bits.u = (bits.u + 1023) << 52;
    return keep * (p * bits.d);
}

}  // namespace regbench
