#pragma once
// Small synthetic pairs for tests that must not depend on the mesh corpus.
#include <cmath>

#include "core/rng.hpp"
#include "core/transform.hpp"
#include "protocols/pair.hpp"

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

/// A pair whose target is T_gt applied to an independent sample of the same surface.
inline Pair SyntheticPair(Eigen::Index n, std::uint64_t seed, const Transform& T_gt) {
    Pair p;
    p.source = BumpyEllipsoid(n, seed);
    p.target = Apply(T_gt, BumpyEllipsoid(n, seed + 1000));
    p.T_gt = T_gt;
    p.source_overlap.setOnes(n);
    p.target_overlap.setOnes(n);
    p.source_overlap_ratio = p.target_overlap_ratio = 1.0;
    p.shape = "bumpy_ellipsoid";
    p.category = "synthetic";
    return p;
}

}  // namespace regbench::testing
