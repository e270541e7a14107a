#pragma once
// Seeded per-pair random number generators: no global RNG anywhere in regbench.
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

namespace regbench {

/// SplitMix64 finaliser (Steele et al. 2014): a bijective 64-bit mixer.
constexpr std::uint64_t SplitMix64(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ULL;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
    return x ^ (x >> 31);
}

/// Seed for pair `pair_index` of a benchmark with seed `benchmark_seed`. Pair k's stream
/// depends only on (seed, k), so adding pairs or running them out of order changes nothing.
constexpr std::uint64_t PairSeed(std::uint64_t benchmark_seed, std::uint64_t pair_index) {
    return SplitMix64(SplitMix64(benchmark_seed) ^ SplitMix64(pair_index + 0x632BE59BD9B4E019ULL));
}

/// A 64-bit Mersenne twister seeded with PairSeed(benchmark_seed, pair_index).
inline std::mt19937_64 MakePairRng(std::uint64_t benchmark_seed, std::uint64_t pair_index) {
    return std::mt19937_64(PairSeed(benchmark_seed, pair_index));
}

/// Uniform double in [lo, hi) computed from raw engine bits, so results are identical across
/// standard libraries (std::uniform_real_distribution is implementation-defined).
inline double UniformReal(std::mt19937_64& rng, double lo, double hi) {
    const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
    return lo + (hi - lo) * u;
}

/// Standard normal via Box-Muller from UniformReal: portable across standard libraries.
inline double StandardNormal(std::mt19937_64& rng) {
    double u1 = UniformReal(rng, 0.0, 1.0);
    while (u1 <= 0.0) u1 = UniformReal(rng, 0.0, 1.0);
    const double u2 = UniformReal(rng, 0.0, 1.0);
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.14159265358979323846 * u2);
}

/// Uniform integer in [0, n) by rejection: portable across standard libraries.
inline std::uint64_t UniformIndex(std::mt19937_64& rng, std::uint64_t n) {
    const std::uint64_t limit =
        std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % n;
    std::uint64_t x = rng();
    while (x >= limit) x = rng();
    return x % n;
}

}  // namespace regbench
