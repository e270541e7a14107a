#pragma once
// Checkpoints: one directory holding the weights (torch::save of every parameter and buffer),
// optionally the optimizer state, and checkpoint.json (full config, model name, training-data
// provenance, regbench version and git hash, steps, validation metrics).
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

// Declared, not included: this header is free of LibTorch's headers, so callers outside networks/
// (the learned methods, the CLI) compile without them (about 20 s of CPU a file).
namespace torch::optim {
class Optimizer;
}  // namespace torch::optim
namespace at {
class Tensor;  // torch::Tensor
}  // namespace at

namespace regbench::networks {

class RegistrationNet;  // networks/net.hpp

constexpr char kCheckpointJson[] = "checkpoint.json";
constexpr char kWeightsFile[] = "weights.pt";
constexpr char kOptimizerFile[] = "optimizer.pt";

/// regbench version and git hash this library was built from.
std::string BuildVersion();
std::string BuildGitSha();

/// Writes `dir` atomically: into dir + ".tmp" (checkpoint.json last), then the old `dir` is
/// renamed to dir + ".old", the new one renamed in and the old one removed, so a kill at any
/// moment leaves a whole checkpoint at `dir`, or at dir.tmp / dir.old for
/// RecoverCheckpointFolder. `dir` may end in "/" ("ck/" is "ck", its temporaries "ck.tmp");
/// ".", ".." and "/" are refused (std::invalid_argument), as is replacing a folder that is not a
/// checkpoint (RequireReplaceableCheckpointFolder). `meta` is stored in checkpoint.json together
/// with "format", "model_config" (net.Config()), "regbench_version" and "git_sha". `optimizer`
/// may be null.
void SaveCheckpoint(const std::string& dir, RegistrationNet& net, const nlohmann::json& meta,
                    torch::optim::Optimizer* optimizer = nullptr);

/// The largest |value| a weight may hold. Trained weights are O(1) to O(1e3); a value above
/// 1e30 (3e38 is float's largest) overflows the first product it enters, and the network then
/// runs on Inf and NaN. Import (import-checkpoint) and load (every checkpoint a method or
/// --resume reads) refuse a tensor holding NaN, Inf or a value beyond it.
constexpr double kMaxAbsWeight = 1e30;

/// "" when every value of `t` is finite and within kMaxAbsWeight (and for a tensor that is not
/// floating point or empty); else what is wrong, in words ("holds NaN", "holds Inf", "holds
/// |w| = 3e+38, beyond the bound 1e+30").
std::string WeightValueProblem(const at::Tensor& t);

/// `dir` without trailing slashes; std::invalid_argument naming it when it is empty, "/", or
/// ends in "." or "..": a checkpoint folder must be a folder of its own.
std::string CheckpointFolderPath(const std::string& dir);

/// Throws std::runtime_error naming `dir` unless it is absent or a folder holding nothing but a
/// checkpoint's files (checkpoint.json, weights.pt, optimizer.pt; empty is fine): a link, a file,
/// a training run folder or any other folder is never replaced or removed by a save.
void RequireReplaceableCheckpointFolder(const std::string& dir);

/// Finishes or undoes a save of `dir` that a kill interrupted: with `dir` missing, a complete
/// dir.tmp is renamed to `dir`, else dir.old is renamed back; then leftover dir.tmp / dir.old
/// (incomplete or superseded) are removed. Returns what it did in words ("" when nothing was
/// left). Call it only while holding the folder's lock (SaveCheckpoint, train --resume).
std::string RecoverCheckpointFolder(const std::string& dir);

/// Reads and checks dir/checkpoint.json (ParseCheckpointJson) and its weights file
/// (CheckWeightsBytes: present, a regular file, not empty, of the recorded size, a whole zip
/// archive). Throws std::runtime_error naming the file when either is missing, not JSON, not a
/// regbench checkpoint, of another format_version, or damaged; with `dir` missing but a save's
/// dir.tmp or dir.old left beside it, the error names them.
nlohmann::json ReadCheckpointJson(const std::string& dir);

/// Loads weights (and the optimizer state when `optimizer` is given) into `net`. Refuses, with a
/// std::runtime_error naming the file, a checkpoint whose model_config differs from
/// net.Config() or whose weights file is missing, corrupt or of other shapes. Returns the JSON.
nlohmann::json LoadCheckpoint(const std::string& dir, RegistrationNet& net,
                              torch::optim::Optimizer* optimizer = nullptr);

/// Builds the network the checkpoint describes (zoo) and loads its weights; eval mode.
/// `inference` (keys of its family's NetworkFamily::inference_params only, networks/family.hpp) is
/// merged over the checkpoint's config first, e.g. {"attention": "full"}; another key is
/// refused (std::invalid_argument naming it).
std::shared_ptr<RegistrationNet> LoadNetFromCheckpoint(
    const std::string& dir, const nlohmann::json& inference = nlohmann::json::object());

/// The zoo config (with "arch") of the checkpoint in `dir` with `inference` merged over it, as
/// LoadNetFromCheckpoint builds it: what ComputeForwardCost (networks/cost.hpp) counts.
nlohmann::json CheckpointNetConfig(const std::string& dir,
                                   const nlohmann::json& inference = nlohmann::json::object());

/// Checks the checkpoint in `dir` without building its network or reading its weights: its
/// checkpoint.json, `inference` as LoadNetFromCheckpoint checks it, and its config by its
/// family's check_config (sizes in range). Returns the family's arch. Throws naming the file.
std::string CheckCheckpointModel(const std::string& dir,
                                 const nlohmann::json& inference = nlohmann::json::object());

}  // namespace regbench::networks
