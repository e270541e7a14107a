#pragma once
// The one registration pair BM_Align times, built (or read) once before any timed loop.
#include <string>

#include "protocols/pair.hpp"

namespace regbench::bench {

/// Environment variable naming an HDF5 pair file (protocols/pair_file.hpp) to time instead of
/// the built-in synthetic pair; REGBENCH_BENCH_PAIR_INDEX picks the pair (default 0).
inline constexpr const char* kPairsEnv = "REGBENCH_BENCH_PAIRS";
inline constexpr const char* kPairIndexEnv = "REGBENCH_BENCH_PAIR_INDEX";

struct BenchPair {
    Pair pair;
    std::string origin;  ///< "synthetic:..." or "<file>#<index>", recorded in the context
};

/// A 717-point partial pair of a smooth synthetic object: a bumpy ellipsoid inside the unit
/// sphere, two independent 1024-point samples, each cropped to 70% by its own half-space
/// (the paper's partial protocol), target moved by 15 degrees about an oblique axis and
/// (0.05, -0.03, 0.02). A moderate motion, so local methods can succeed and rre_deg shows it.
Pair MakeSyntheticPair();

/// The pair from REGBENCH_BENCH_PAIRS when set, else MakeSyntheticPair(). Loaded on first use
/// and cached. Throws std::runtime_error naming the file or index when they are unusable.
const BenchPair& GetBenchPair();

}  // namespace regbench::bench
