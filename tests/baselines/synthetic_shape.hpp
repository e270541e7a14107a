#pragma once
// Test-only synthetic object: a smooth bumpy ellipsoid inside the unit sphere, sampled with
// the portable RNG, plus the protocol's half-space crop. Self-contained on purpose (the
// protocol layer's mesh sampler is another component).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "core/point_cloud.hpp"
#include "core/rng.hpp"

namespace regbench::testing {

/// Uniform direction on the unit sphere (normalised Gaussian vector).
inline Eigen::Vector3d RandomDirection(std::mt19937_64& rng) {
    Eigen::Vector3d u(StandardNormal(rng), StandardNormal(rng), StandardNormal(rng));
    return u.normalized();
}

/// `n` points on r(u) * diag(0.8, 0.55, 0.4) u with a smooth bump r(u) in [0.88, 1.12]:
/// no symmetry axis, so rotations are observable; max radius < 0.9.
inline PointCloud SampleBumpyEllipsoid(std::mt19937_64& rng, Eigen::Index n) {
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

/// Keeps the round(keep * N) points farthest along a random direction from the centroid
/// (the protocol's crop).
inline PointCloud CropHalfSpace(std::mt19937_64& rng, const PointCloud& points, double keep) {
    const Eigen::Vector3d n = RandomDirection(rng);
    const Eigen::RowVector3d centroid = points.colwise().mean();
    const Eigen::VectorXd score = (points.rowwise() - centroid) * n;
    std::vector<Eigen::Index> order(static_cast<std::size_t>(points.rows()));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](Eigen::Index a, Eigen::Index b) { return score(a) > score(b); });
    const auto kept =
        static_cast<Eigen::Index>(std::lround(keep * static_cast<double>(points.rows())));
    PointCloud out(kept, 3);
    for (Eigen::Index i = 0; i < kept; ++i)
        out.row(i) = points.row(order[static_cast<std::size_t>(i)]);
    return out;
}

/// 1024 samples cropped to 70%: 717 points, as the paper's partial protocol.
inline PointCloud PartialCloud(std::mt19937_64& rng) {
    constexpr Eigen::Index kSampled = 1024;
    constexpr double kKeep = 0.7;
    return CropHalfSpace(rng, SampleBumpyEllipsoid(rng, kSampled), kKeep);
}

}  // namespace regbench::testing
