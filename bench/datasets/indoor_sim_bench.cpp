// Indoor scan simulation: wall time per generated pair, and the overlap distribution of the
// generated pairs (docs/indoor-simulation.md).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/kd_tree.hpp"
#include "core/rng.hpp"
#include "datasets/indoor_sim.hpp"
#include "protocols/pair_protocols.hpp"

namespace regbench {
namespace {

constexpr std::uint64_t kSeed = 2023;
constexpr Eigen::Index kResampledPoints = 2048;  // paper Tab. 3: 2048 points per scan
constexpr double kKeep = 0.7;                    // then cropped to 70% (1433 points)

const FurnitureLibrary& Library() {
    static const FurnitureLibrary library =
        LoadFurnitureMeshes(std::string(REGBENCH_SOURCE_DIR) + "/data/meshes");
    return library;
}

/// Default options with the image width set (height 3/4 of it, focal scaled from 525 @ 640).
IndoorSimOptions WithWidth(int width) {
    IndoorSimOptions o;
    o.image_width = width;
    o.image_height = width * 3 / 4;
    o.fx = o.fy = 525.0 * width / 640.0;
    o.cx = 0.5 * (o.image_width - 1);
    o.cy = 0.5 * (o.image_height - 1);
    o.min_valid_points = std::min(o.min_valid_points, o.image_width * o.image_height / 8);
    return o;
}

/// `n` distinct rows drawn uniformly (partial Fisher-Yates with UniformIndex), all if fewer.
PointCloud Resample(const PointCloud& points, Eigen::Index n, std::mt19937_64& rng) {
    std::vector<Eigen::Index> order(static_cast<std::size_t>(points.rows()));
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<Eigen::Index>(i);
    const Eigen::Index m = std::min(n, points.rows());
    PointCloud out(m, 3);
    for (Eigen::Index i = 0; i < m; ++i) {
        const auto j = static_cast<std::size_t>(i) +
                       UniformIndex(rng, static_cast<std::uint64_t>(order.size() - i));
        std::swap(order[static_cast<std::size_t>(i)], order[j]);
        out.row(i) = points.row(order[static_cast<std::size_t>(i)]);
    }
    return out;
}

/// The protocol's crop (protocols/pair_protocols.hpp).
PointCloud Crop(const PointCloud& points, double keep, std::mt19937_64& rng) {
    return Gather(points, CropIndices(points, keep, rng));
}

void BM_SimulateIndoorPair(benchmark::State& state) {
    const IndoorSimOptions o = WithWidth(static_cast<int>(state.range(0)));
    const FurnitureLibrary& library = Library();
    std::uint64_t k = 0;
    double points = 0.0;
    for (auto _ : state) {
        std::mt19937_64 rng = MakePairRng(kSeed, k++);
        const IndoorScanPair pair = SimulateIndoorPair(o, library, rng);
        points += static_cast<double>(pair.a.points_camera.rows() + pair.b.points_camera.rows());
        benchmark::DoNotOptimize(pair.a.points_camera.data());
    }
    state.counters["points_per_scan"] = points / (2.0 * static_cast<double>(k));
}
BENCHMARK(BM_SimulateIndoorPair)
    ->Arg(160)
    ->Arg(320)
    ->ArgNames({"width"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(10);

struct Summary {
    double mean = 0.0, min = 1.0, max = 0.0, median = 0.0;
    std::array<int, 10> histogram{};  ///< bins of width 0.1 on [0, 1]
};

Summary Summarise(std::vector<double> values) {
    Summary s;
    for (double v : values) {
        s.mean += v / static_cast<double>(values.size());
        s.min = std::min(s.min, v);
        s.max = std::max(s.max, v);
        ++s.histogram[static_cast<std::size_t>(std::min(9, static_cast<int>(v * 10.0)))];
    }
    std::sort(values.begin(), values.end());
    s.median = values[values.size() / 2];
    return s;
}

void Report(benchmark::State& state, const std::string& prefix, const Summary& s,
            std::string& label) {
    state.counters[prefix + "_mean"] = s.mean;
    state.counters[prefix + "_min"] = s.min;
    state.counters[prefix + "_median"] = s.median;
    state.counters[prefix + "_max"] = s.max;
    label += prefix + " hist[0-1 by 0.1]=";
    for (int count : s.histogram) label += std::to_string(count) + ",";
    label.back() = ' ';
}

/// Overlap of the first range(0) pairs: fraction of A's points with a point of B within eta
/// after T_gt, on the full scans (eta = 0.05 m, the stored labels) and after resampling each
/// scan to 2048 points (eta = 0.05 m and 0.1 m), and after also cropping each resampled scan
/// to 70% (1433 points, eta = 0.1 m), as the paper's Tab. 3 inputs would see it.
void BM_IndoorOverlapSurvey(benchmark::State& state) {
    const IndoorSimOptions o = WithWidth(static_cast<int>(state.range(1)));
    const FurnitureLibrary& library = Library();
    std::vector<double> full, resampled_005, resampled_010, cropped_010;
    for (auto _ : state) {
        for (std::int64_t k = 0; k < state.range(0); ++k) {
            std::mt19937_64 rng = MakePairRng(kSeed, static_cast<std::uint64_t>(k));
            const IndoorScanPair pair = SimulateIndoorPair(o, library, rng);
            full.push_back(pair.a_overlap_ratio);
            const PointCloud a = Resample(pair.a.points_camera, kResampledPoints, rng);
            const PointCloud b = Resample(pair.b.points_camera, kResampledPoints, rng);
            resampled_005.push_back(OverlapLabels(a, b, pair.T_b_a, 0.05).cast<double>().mean());
            resampled_010.push_back(OverlapLabels(a, b, pair.T_b_a, 0.10).cast<double>().mean());
            const PointCloud a_crop = Crop(a, kKeep, rng);
            const PointCloud b_crop = Crop(b, kKeep, rng);
            cropped_010.push_back(
                OverlapLabels(a_crop, b_crop, pair.T_b_a, 0.10).cast<double>().mean());
        }
    }
    std::string label;
    Report(state, "full_eta005", Summarise(full), label);
    Report(state, "n2048_eta005", Summarise(resampled_005), label);
    Report(state, "n2048_eta010", Summarise(resampled_010), label);
    Report(state, "n1433_crop_eta010", Summarise(cropped_010), label);
    state.SetLabel(label);
}
BENCHMARK(BM_IndoorOverlapSurvey)
    ->Args({100, 320})
    ->ArgNames({"pairs", "width"})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

}  // namespace
}  // namespace regbench
