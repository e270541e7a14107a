#pragma once
// One training pair, what the trainer (networks/training/train.hpp) reads and the batcher
// (networks/training/train_batch.hpp) stacks. Free of LibTorch types.
#include <Eigen/Core>

#include "core/point_cloud.hpp"

namespace regbench::networks {

/// One training or validation pair (the protocol layer's Pair, minus what training never uses).
struct TrainSample {
    PointCloud source;
    PointCloud target;
    Transform T_gt = Transform::Identity();  ///< maps source into the target frame
    Eigen::VectorXd source_overlap;          ///< 0/1 per source point (may be empty)
    Eigen::VectorXd target_overlap;          ///< 0/1 per target point (may be empty)
};

}  // namespace regbench::networks
