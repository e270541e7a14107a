#pragma once
// The LibTorch side of ogmm/train.hpp (which callers outside ogmm/ include without LibTorch's
// headers): training samples stacked into a network batch.
#include <torch/torch.h>

#include <vector>

#include "ogmm/net.hpp"
#include "ogmm/train.hpp"

namespace regbench::ogmm {

/// Stacks samples into a batch (same point counts required; names the first mismatch).
PairBatch Collate(const std::vector<TrainSample>& samples, const torch::Device& device);

}  // namespace regbench::ogmm
