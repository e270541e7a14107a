#pragma once
// Seeded synthetic shapes, motions and pose errors shared by tests and benchmarks (the
// header-only regbench_testing target). Depends on core/ only, so every test folder may use it.
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/point_cloud.hpp"
#include "core/rng.hpp"
#include "core/transform.hpp"

namespace regbench::testing {

/// n points on a bumpy ellipsoid surface (semi-axes 0.9/0.6/0.4), deterministic in `seed`.
inline PointCloud BumpyEllipsoid(Eigen::Index n, std::uint64_t seed) {
    auto rng = MakePairRng(seed, 0);
    PointCloud p(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        const double z = UniformReal(rng, -1.0, 1.0);
        const double phi = UniformReal(rng, 0.0, 2.0 * M_PI);
        const double r = std::sqrt(1.0 - z * z);
        const double bump = 1.0 + 0.1 * std::sin(3.0 * phi) * std::cos(2.0 * z);
        p.row(i) << 0.9 * bump * r * std::cos(phi), 0.6 * bump * r * std::sin(phi), 0.4 * bump * z;
    }
    return p;
}

/// n points on the plain ellipsoid surface of the probabilistic-baselines spec (semi-axes
/// 0.9/0.6/0.4), directions from a normal draw; deterministic in `seed`.
inline PointCloud EllipsoidSurface(Eigen::Index n, std::uint64_t seed) {
    auto rng = MakePairRng(seed, 0);
    PointCloud p(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        Eigen::Vector3d v(StandardNormal(rng), StandardNormal(rng), StandardNormal(rng));
        v.normalize();
        p.row(i) << 0.9 * v.x(), 0.6 * v.y(), 0.4 * v.z();
    }
    return p;
}

/// n points on an asymmetric, lumpy ellipsoid (semi-axes ~0.9/0.6/0.4): no symmetry that
/// would make a 30-degree motion ambiguous.
inline PointCloud LumpyEllipsoid(int n, std::uint64_t seed) {
    auto rng = MakePairRng(seed, 0);
    PointCloud P(n, 3);
    for (int i = 0; i < n; ++i) {
        Eigen::Vector3d u(StandardNormal(rng), StandardNormal(rng), StandardNormal(rng));
        u.normalize();
        const double r = 1.0 + 0.25 * u.x() * u.y() + 0.2 * u.z() * u.z() * u.z() + 0.15 * u.x();
        P.row(i) = (r * Eigen::Vector3d(0.9 * u.x(), 0.6 * u.y(), 0.4 * u.z())).transpose();
    }
    return P;
}

/// The spec's test motion: R(30 deg about z), t = (0.1, -0.05, 0.2).
inline Transform ThirtyDegreesAboutZ() {
    return MakeTransform(RotationFromEulerZyxDeg(30.0, 0.0, 0.0), Eigen::Vector3d(0.1, -0.05, 0.2));
}

/// The crop protocol in miniature: keep the points with x below the 70% quantile, add
/// N(0, jitter^2) noise per coordinate.
inline PointCloud CropAndJitter(const PointCloud& P, double keep, double jitter,
                                std::uint64_t seed) {
    std::vector<double> xs;
    for (Eigen::Index i = 0; i < P.rows(); ++i) xs.push_back(P(i, 0));
    std::sort(xs.begin(), xs.end());
    const double cut = xs[static_cast<size_t>(keep * static_cast<double>(xs.size() - 1))];
    auto rng = MakePairRng(seed, 1);
    PointCloud out(P.rows(), 3);
    Eigen::Index n = 0;
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
        if (P(i, 0) > cut) continue;
        for (int d = 0; d < 3; ++d) out(n, d) = P(i, d) + jitter * StandardNormal(rng);
        ++n;
    }
    return out.topRows(n);
}

inline double RotationErrorDeg(const Transform& a, const Transform& b) {
    return RotationAngleDeg(a.topLeftCorner<3, 3>(), b.topLeftCorner<3, 3>());
}

inline double TranslationError(const Transform& a, const Transform& b) {
    return (a.topRightCorner<3, 1>() - b.topRightCorner<3, 1>()).norm();
}

}  // namespace regbench::testing
