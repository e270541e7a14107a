#pragma once
// Training pairs for networks/ tests without the protocol layer: a bumpy ellipsoid (core's
// sampler), two 70% half-space crops of one sample, a motion of up to 45 degrees per Euler axis
// and 0.5 translation per axis on the source (the authors' shared pairing, simplified).
#include <algorithm>
#include <numeric>
#include <vector>

#include "core/rng.hpp"
#include "core/synthetic_shapes.hpp"
#include "core/transform.hpp"
#include "networks/training/train.hpp"

namespace regbench::networks::testing {

inline PointCloud KeepAlong(const PointCloud& c, const Eigen::Vector3d& dir, Eigen::Index keep) {
    std::vector<Eigen::Index> idx(c.rows());
    std::iota(idx.begin(), idx.end(), 0);
    const Eigen::Vector3d mean = c.colwise().mean().transpose();
    std::stable_sort(idx.begin(), idx.end(), [&](Eigen::Index a, Eigen::Index b) {
        return (c.row(a).transpose() - mean).dot(dir) > (c.row(b).transpose() - mean).dot(dir);
    });
    PointCloud out(keep, 3);
    for (Eigen::Index i = 0; i < keep; ++i) out.row(i) = c.row(idx[i]);
    return out;
}

/// Pair `index` of stream `seed`: `points` sampled, each cloud keeps 70% of them.
inline TrainSample SyntheticPair(std::uint64_t seed, std::uint64_t index, Eigen::Index points,
                                 double max_deg = 45.0) {
    std::mt19937_64 rng = MakePairRng(seed, index);
    const PointCloud shape = BumpyEllipsoidSurface(rng, points);
    const auto keep = static_cast<Eigen::Index>(0.7 * static_cast<double>(points) + 0.5);
    const PointCloud a = KeepAlong(shape, RandomDirection(rng), keep);
    const PointCloud b = KeepAlong(shape, RandomDirection(rng), keep);
    const Eigen::Matrix3d R = RotationXyzProductDeg(
        UniformReal(rng, 0, max_deg), UniformReal(rng, 0, max_deg), UniformReal(rng, 0, max_deg));
    const Eigen::Vector3d t(UniformReal(rng, -0.5, 0.5), UniformReal(rng, -0.5, 0.5),
                            UniformReal(rng, -0.5, 0.5));
    const Transform motion = MakeTransform(R, t);  // applied to the source
    TrainSample s;
    s.source = Apply(motion, a);
    s.target = b;
    s.T_gt = InvertRigid(motion);
    s.source_overlap = Eigen::VectorXd::Ones(keep);
    s.target_overlap = Eigen::VectorXd::Ones(keep);
    return s;
}

inline TrainData SyntheticData(std::uint64_t seed, Eigen::Index points, int val_pairs) {
    TrainData d;
    d.train_pair = [seed, points](std::uint64_t k) { return SyntheticPair(seed, k, points); };
    for (int i = 0; i < val_pairs; ++i) d.validation.push_back(SyntheticPair(seed + 1, i, points));
    d.provenance = {{"synthetic", "bumpy ellipsoid"}, {"seed", seed}};
    return d;
}

}  // namespace regbench::networks::testing
