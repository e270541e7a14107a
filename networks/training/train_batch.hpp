#pragma once
// The LibTorch side of training (networks/training/train.hpp is free of LibTorch's headers):
// training samples stacked into a network batch.
#include <torch/torch.h>

#include <vector>

#include "networks/net.hpp"
#include "networks/training/sample.hpp"

namespace regbench::networks {

/// Stacks samples into a batch (same point counts required; names the first mismatch).
PairBatch Collate(const std::vector<TrainSample>& samples, const torch::Device& device);

}  // namespace regbench::networks
