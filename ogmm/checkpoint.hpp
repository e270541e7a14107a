#pragma once
// Checkpoints: one directory holding the weights (torch::save of every parameter and buffer),
// optionally the optimizer state, and checkpoint.json (full config, model name, training-data
// provenance, regbench version and git hash, steps, validation metrics).
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "ogmm/net.hpp"

namespace regbench::ogmm {

constexpr char kCheckpointJson[] = "checkpoint.json";
constexpr char kWeightsFile[] = "weights.pt";
constexpr char kOptimizerFile[] = "optimizer.pt";

/// regbench version and git hash this library was built from.
std::string BuildVersion();
std::string BuildGitSha();

/// Writes `dir` atomically (into dir + ".tmp", then renamed over any old `dir`). `meta` is stored
/// in checkpoint.json together with "format", "model_config" (net.Config()), "regbench_version"
/// and "git_sha". `optimizer` may be null.
void SaveCheckpoint(const std::string& dir,
                    RegistrationNet& net,
                    const nlohmann::json& meta,
                    torch::optim::Optimizer* optimizer = nullptr);

/// Reads and checks dir/checkpoint.json. Throws std::runtime_error naming the file when it is
/// missing, not JSON or not a regbench checkpoint.
nlohmann::json ReadCheckpointJson(const std::string& dir);

/// Loads weights (and the optimizer state when `optimizer` is given) into `net`. Refuses, with a
/// std::runtime_error naming the file, a checkpoint whose model_config differs from
/// net.Config() or whose weights file is missing, corrupt or of other shapes. Returns the JSON.
nlohmann::json LoadCheckpoint(const std::string& dir,
                              RegistrationNet& net,
                              torch::optim::Optimizer* optimizer = nullptr);

/// Builds the network the checkpoint describes (zoo) and loads its weights; eval mode.
std::shared_ptr<RegistrationNet> LoadNetFromCheckpoint(const std::string& dir);

}  // namespace regbench::ogmm
