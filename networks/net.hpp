#pragma once
// The contract between the learned registration networks (DeepGMR, OGMM) and the code that
// trains them, saves them and runs them as regbench methods. One network = one subclass of
// RegistrationNet; training, checkpoints and inference only ever see this interface.
#include <torch/torch.h>

#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

namespace regbench::networks {

/// A batch of registration pairs, row-vector points like DeepGMR's code. Fields a network does
/// not need may be undefined tensors; ground truth is present only in training and validation.
struct PairBatch {
    torch::Tensor source;          ///< [B, N, 3] float32
    torch::Tensor target;          ///< [B, M, 3] float32
    torch::Tensor T_gt;            ///< [B, 4, 4] float32, maps source into target (training only)
    torch::Tensor source_overlap;  ///< [B, N] float32 0/1 labels (training only, may be undefined)
    torch::Tensor target_overlap;  ///< [B, M] float32 0/1 labels (training only, may be undefined)
    /// Random choices (FPS starts) draw from this generator; unset: torch's global RNG (which
    /// training seeds per step). Inference sets one per pair, since several runner threads
    /// share a network and a process-wide RNG would make the draws depend on their timing.
    c10::optional<at::Generator> generator;
};

/// What a forward pass returns: the estimated transform plus whatever the network's loss needs.
struct NetOutput {
    torch::Tensor T;                           ///< [B, 4, 4] estimated T_target_source
    std::map<std::string, torch::Tensor> aux;  ///< network-specific intermediates
};

/// Loss terms by name; "total" is the one to back-propagate, the others are logged.
using LossTerms = std::map<std::string, torch::Tensor>;

class RegistrationNet : public torch::nn::Module {
public:
    /// Forward pass on a batch. Random choices (FPS starts) draw from batch.generator, else the
    /// torch global RNG.
    virtual NetOutput Forward(const PairBatch& batch) = 0;
    /// Training loss from a forward output and the batch's ground truth.
    virtual LossTerms Loss(const PairBatch& batch, const NetOutput& output) = 0;
    /// The full configuration this network was built from (stored in checkpoints; building a
    /// network from it again gives the same architecture).
    virtual nlohmann::json Config() const = 0;
};

}  // namespace regbench::networks
