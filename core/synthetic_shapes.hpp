#pragma once
// Seeded synthetic shapes for tests and benchmarks (no data files needed).
#include <Eigen/Core>
#include <cmath>
#include <random>

#include "core/point_cloud.hpp"
#include "core/rng.hpp"

namespace regbench {

/// n points on a smooth, closed, asymmetric unit-scale surface: the ellipsoid with semi-axes
/// 0.9 / 0.6 / 0.4 (as in the spec's lattice measurement) with a radial modulation
/// 1 + 0.25 u_x u_y + 0.2 u_z^3 + 0.1 u_x, so no rotation maps it onto itself. Directions u
/// are uniform on the sphere (normalised Gaussians from core/rng.hpp: portable).
inline PointCloud SmoothBlobSurface(std::mt19937_64& rng, Eigen::Index n) {
    PointCloud p(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        Eigen::Vector3d u;
        do {
            u = Eigen::Vector3d(StandardNormal(rng), StandardNormal(rng), StandardNormal(rng));
        } while (u.norm() < 1e-9);
        u.normalize();
        const double radial =
            1.0 + 0.25 * u.x() * u.y() + 0.2 * u.z() * u.z() * u.z() + 0.1 * u.x();
        p.row(i) = (Eigen::Vector3d(0.9, 0.6, 0.4).cwiseProduct(u) * radial).transpose();
    }
    return p;
}

/// Uniform direction on the unit sphere (normalised Gaussian vector, portable draws).
inline Eigen::Vector3d RandomDirection(std::mt19937_64& rng) {
    return Eigen::Vector3d(StandardNormal(rng), StandardNormal(rng), StandardNormal(rng))
        .normalized();
}

/// n points on r(u) * diag(0.8, 0.55, 0.4) u with a smooth bump r(u) in [0.88, 1.12]: no
/// symmetry axis, so rotations are observable; every point inside the unit sphere (< 0.9).
inline PointCloud BumpyEllipsoidSurface(std::mt19937_64& rng, Eigen::Index n) {
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

/// n points uniform in the axis-aligned box [lo, hi]^3.
inline PointCloud UniformBox(std::mt19937_64& rng, Eigen::Index n, const Eigen::Vector3d& lo,
                             const Eigen::Vector3d& hi) {
    PointCloud p(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) p(i, k) = UniformReal(rng, lo[k], hi[k]);
    }
    return p;
}

}  // namespace regbench
