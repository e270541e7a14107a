#pragma once
// Test-only partial clouds: core's bumpy ellipsoid, cropped with the protocol layer's crop.
#include "core/point_cloud.hpp"
#include "core/synthetic_shapes.hpp"
#include "protocols/pair_protocols.hpp"

namespace regbench::testing {

/// `n` points on core's bumpy ellipsoid (BumpyEllipsoidSurface).
inline PointCloud SampleBumpyEllipsoid(std::mt19937_64& rng, Eigen::Index n) {
    return BumpyEllipsoidSurface(rng, n);
}

/// 1024 samples cropped to 70% with the partial protocol's crop: 717 points.
inline PointCloud PartialCloud(std::mt19937_64& rng) {
    constexpr Eigen::Index kSampled = 1024;
    constexpr double kKeep = 0.7;
    const PointCloud full = BumpyEllipsoidSurface(rng, kSampled);
    return Gather(full, CropIndices(full, kKeep, rng));
}

}  // namespace regbench::testing
