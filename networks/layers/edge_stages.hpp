#pragma once
// The DGCNN's edge stages in training: rows [M, C0] of M = P k edges (k consecutive rows per
// point, channels last) go through a chain of bias-free 1x1 convolutions, each followed by
// BatchNorm with the batch's statistics and ReLU; every stage's output is max-pooled over the k
// neighbours and the pooled maps are concatenated: [P, C1 + C2 + ...].
//
// Two implementations with the same contract:
//  - EdgeStagesReference: the LibTorch composition (mm, batch_norm, relu_, max with indices, cat)
//    that DgcnnImpl ran before; the reference the tests hold the fused one to.
//  - EdgeStagesFused: one custom autograd Function over the whole chain. Per stage the forward
//    makes three passes over the [M, C] map (the GEMM, one pass for the batch statistics, one
//    that normalises, applies ReLU and pools with argmax while writing the next stage's input)
//    and the backward two (one reduction for sum(g) and sum(g (y - mean)), one that writes the
//    input gradient), with the max's sparse gradient added straight into the dense one from the
//    next stage (LibTorch: a zero-filled scatter, an add, ReLU's backward and BatchNorm's
//    backward, each its own pass; docs/performance.md, section 6).
//
// Both update BatchNorm's running statistics exactly as BatchNorm2d does in training
// (running = (1 - momentum) running + momentum batch, the variance unbiased, and
// num_batches_tracked + 1). Ties of the max over k go to the first neighbour (lowest index), as
// torch::max's indices do on the CPU; a NaN is not propagated by the fused max (NaN features
// have already broken a training run).
#include <torch/torch.h>

#include <cstdint>
#include <vector>

namespace regbench::networks {

/// One stage's parameters and BatchNorm state (tensors share storage with the modules').
struct EdgeStage {
    torch::Tensor weight;              ///< [C_out, C_in], the 1x1 convolution's weight
    torch::Tensor bn_weight, bn_bias;  ///< [C_out]
    torch::Tensor running_mean, running_var, num_batches_tracked;  ///< updated in place
    double momentum = 0.1;
    double eps = 1e-5;
};

/// A stage from a bias-free 1x1 Conv2d and its BatchNorm2d (momentum 0.1 when unset, as
/// DgcnnImpl always ran it).
EdgeStage EdgeStageOf(const torch::nn::Conv2d& conv, const torch::nn::BatchNorm2d& bn);

/// LibTorch composition: per stage mm -> batch_norm (training) -> relu_ -> max over k; cat.
/// rows [P k, C0] -> [P, sum C_s].
torch::Tensor EdgeStagesReference(const torch::Tensor& rows, const std::vector<EdgeStage>& stages,
                                  int64_t k);

/// The same as one custom autograd Function (CPU, float or double, contiguous rows).
torch::Tensor EdgeStagesFused(const torch::Tensor& rows, const std::vector<EdgeStage>& stages,
                              int64_t k);

/// Whether DgcnnImpl uses EdgeStagesFused in training (default) or the reference composition.
/// Process-wide; for tests that compare whole training runs of the two.
void SetFusedEdgeStages(bool enabled);
bool FusedEdgeStages();

}  // namespace regbench::networks
