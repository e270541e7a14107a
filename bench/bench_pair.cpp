#include "bench/bench_pair.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "core/rng.hpp"
#include "core/transform.hpp"
#include "protocols/pair_file.hpp"

namespace regbench::bench {
namespace {

constexpr std::uint64_t kSeed = 20230103;  // fixed: the timed pair never changes
constexpr Eigen::Index kSampledPoints = 1024;
constexpr double kKeepRatio = 0.7;  // 1024 -> 717, the paper's partial protocol
constexpr double kRotationDeg = 15.0;

Eigen::Vector3d RandomDirection(std::mt19937_64& rng) {
    return Eigen::Vector3d(StandardNormal(rng), StandardNormal(rng), StandardNormal(rng))
        .normalized();
}

/// r(u) * diag(0.8, 0.55, 0.4) u with a smooth bump r in [0.88, 1.12]: no symmetry axis,
/// every point inside the unit sphere.
PointCloud SampleObject(std::mt19937_64& rng, Eigen::Index n) {
    const Eigen::Vector3d axes(0.8, 0.55, 0.4);
    PointCloud points(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        const Eigen::Vector3d u = RandomDirection(rng);
        const double bump =
            1.0 + 0.12 * std::sin(3.0 * u.x()) * std::cos(2.0 * u.y() + 0.5 * u.z());
        points.row(i) = (bump * axes.cwiseProduct(u)).transpose();
    }
    return points;
}

/// Keeps the round(keep * N) points farthest from the centroid along a random direction.
PointCloud Crop(std::mt19937_64& rng, const PointCloud& points) {
    const Eigen::Vector3d n = RandomDirection(rng);
    const Eigen::RowVector3d centroid = points.colwise().mean();
    const Eigen::VectorXd score = (points.rowwise() - centroid) * n;
    std::vector<Eigen::Index> order(static_cast<std::size_t>(points.rows()));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](Eigen::Index a, Eigen::Index b) { return score(a) > score(b); });
    const auto kept =
        static_cast<Eigen::Index>(std::lround(kKeepRatio * static_cast<double>(points.rows())));
    PointCloud out(kept, 3);
    for (Eigen::Index i = 0; i < kept; ++i) {
        out.row(i) = points.row(order[static_cast<std::size_t>(i)]);
    }
    return out;
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
    pair.source = Crop(rng, SampleObject(rng, kSampledPoints));
    const PointCloud target_local = Crop(rng, SampleObject(rng, kSampledPoints));
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
