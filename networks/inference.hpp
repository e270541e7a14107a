#pragma once
// One network call on one registration pair, as the learned methods (baselines/learned.cpp) run
// it. Free of LibTorch types, so callers outside networks/ compile without its headers.
#include <cstdint>
#include <map>
#include <string>

#include "core/point_cloud.hpp"

namespace regbench::networks {

class RegistrationNet;

struct PairEstimate {
    /// The network's T_target_source in double. The networks compute in float32, so their R is
    /// orthonormal only to ~1e-7; it is replaced by the nearest rotation (R = U diag(1, 1,
    /// det(U V^T)) V^T from the SVD, a change of the same ~1e-7 order), so the estimate is
    /// exactly rigid like every other method's.
    Transform T = Transform::Identity();
    /// Per-source-point outputs (overlap scores and the like), each by its mean.
    std::map<std::string, double> source_point_means;
};

/// Runs `net` (eval mode expected) on one pair without gradients, on `threads` LibTorch and
/// BLAS threads. Random choices (FPS starts) draw from a generator seeded with `seed` that
/// belongs to this call, so threads sharing `net` do not change each other's draws.
PairEstimate EstimatePair(RegistrationNet& net, const PointCloud& source, const PointCloud& target,
                          std::uint64_t seed, int threads);

}  // namespace regbench::networks
