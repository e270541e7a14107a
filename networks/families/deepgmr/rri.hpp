#pragma once
// Rotation-invariant point features (RRI, Chen et al. CVPR 2019) as DeepGMR's data loader computes
// them; see docs/learned-methods.md ("RRI features").
#include <torch/torch.h>

#include <Eigen/Core>
#include <string>

#include "core/enum_names.hpp"
#include "core/point_cloud.hpp"

namespace regbench::networks {

/// Orientation of the neighbour angle phi. DeepGMR's CUDA kernel (used whenever CUDA exists, so
/// for the released models) takes atan2((T_j x T_m) . p_hat, T_j . T_m); its numpy fallback the
/// mirror image (T_m x T_j).
enum class RriVariant { kCuda, kNumpy };
REGBENCH_CHOICES(RriVariant, {{RriVariant::kCuda, "cuda"}, {RriVariant::kNumpy, "numpy"}})

/// RRI features of one cloud: row i holds 4k values, entry 4j+f with f in (r_p, r_q_j, theta_j,
/// phi_j) for the j-th nearest neighbour (self excluded) of point i of the *centred* cloud.
/// Needs at least k + 1 points; a point at the centroid gives NaN, as the original does.
Eigen::MatrixXd RriFeatures(const PointCloud& cloud, int k = 20, RriVariant v = RriVariant::kCuda);

/// Batched version for the network: xyz [B, N, 3] (any device, float) -> [B, 4k, N] float32 on
/// xyz's device. Computed without gradient.
torch::Tensor RriFeatureTensor(const torch::Tensor& xyz, int k, RriVariant v);

}  // namespace regbench::networks
