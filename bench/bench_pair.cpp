#include "bench/bench_pair.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "core/rng.hpp"
#include "core/synthetic_shapes.hpp"
#include "core/transform.hpp"
#include "protocols/pair_file.hpp"
#include "protocols/pair_protocols.hpp"

namespace regbench::bench {
namespace {

constexpr std::uint64_t kSeed = 20230103;  // fixed: the timed pair never changes
constexpr Eigen::Index kSampledPoints = 1024;
constexpr double kKeepRatio = 0.7;  // 1024 -> 717, the paper's partial protocol
constexpr double kRotationDeg = 15.0;

/// 1024 samples of core's bumpy ellipsoid, cropped with the partial protocol's crop: 717.
PointCloud PartialSample(std::mt19937_64& rng) {
    const PointCloud full = BumpyEllipsoidSurface(rng, kSampledPoints);
    return Gather(full, CropIndices(full, kKeepRatio, rng));
}

BenchPair LoadPair() {
    const char* path = std::getenv(kPairsEnv);
    if (path == nullptr || *path == '\0') {
        return {MakeSyntheticPair(), "synthetic:bumpy-ellipsoid,717+717,15deg"};
    }
    const char* index_text = std::getenv(kPairIndexEnv);
    std::size_t index = 0;
    if (index_text != nullptr && *index_text != '\0') {
        char* end = nullptr;
        const unsigned long long parsed = std::strtoull(index_text, &end, 10);
        if (end == index_text || *end != '\0') {
            throw std::runtime_error(std::string(kPairIndexEnv) + "='" + index_text +
                                     "' is not a pair index");
        }
        index = static_cast<std::size_t>(parsed);
    }
    PairSet set = ReadPairFile(path);
    if (index >= set.pairs.size()) {
        throw std::runtime_error(std::string(path) + ": pair " + std::to_string(index) +
                                 " requested, file holds " + std::to_string(set.pairs.size()));
    }
    return {std::move(set.pairs[index]), std::string(path) + "#" + std::to_string(index)};
}

}  // namespace

Pair MakeSyntheticPair() {
    auto rng = MakePairRng(kSeed, 0);
    Pair pair;
    pair.source = PartialSample(rng);
    const PointCloud target_local = PartialSample(rng);
    const Eigen::Matrix3d R =
        RotationFromAxisAngle({1.0, -0.6, 0.8}, kRotationDeg * 3.14159265358979323846 / 180.0);
    pair.T_gt = MakeTransform(R, {0.05, -0.03, 0.02});
    pair.target = Apply(pair.T_gt, target_local);
    pair.shape = "bumpy-ellipsoid";
    pair.category = "synthetic";
    return pair;
}

const BenchPair& GetBenchPair() {
    static const BenchPair pair = LoadPair();
    return pair;
}

}  // namespace regbench::bench
