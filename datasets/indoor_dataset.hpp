#pragma once
// `indoor-sim`: simulated depth scans standing in for 7Scenes / ICL-NUIM when those are absent.
#include <string>
#include <vector>

#include "datasets/dataset.hpp"
#include "protocols/shape_source.hpp"

namespace regbench {

/// Number of simulated scenes: scenes [0, 24) are train, [24, 30) val, [30, 40) test.
constexpr int kIndoorSimScenes = 40;

/// One scan per scene (SimulateIndoorScan with the default options at 160 x 120 pixels, a
/// Kinect downscaled by 4: ~16k points, plenty for the protocol's 2048-point resampling),
/// seeded from (options.seed, scene index), furniture from <data dir>/meshes. Points are raw
/// metres in the camera frame, like 7Scenes. The `indoor` protocol resamples each scan twice.
/// Splits: all, train, val, test. Throws std::invalid_argument for another split.
std::vector<ShapeSource> LoadIndoorSimShapes(const std::string& split,
                                             const DatasetOptions& options);

}  // namespace regbench
