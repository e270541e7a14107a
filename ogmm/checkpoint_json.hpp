#pragma once
// checkpoint.json without LibTorch: parsing and every check of its contents, so the reader can
// be fuzzed in the sanitizer build (which has no LibTorch; fuzz/fuzz_checkpoint_json.cpp).
#include <nlohmann/json.hpp>
#include <string>

namespace regbench::ogmm {

/// Parses `text` (the bytes of checkpoint.json at `path`) depth-limited and checks it: a JSON
/// object with "format" = regbench-checkpoint and a "model_config" object; "config", when
/// present, an object whose "arch" (when present) is a string; "trainer", when present, passes
/// CheckTrainerStateJson. Throws std::runtime_error naming `path` and the key.
nlohmann::json ParseCheckpointJson(const std::string& text, const std::string& path);

/// The trainer counters as written: "step" present; step, planned_steps, pairs_seen,
/// plateau_bad and epoch_loss_steps whole numbers in [0, 2^53] (plateau_bad <= 1e9); lr,
/// elapsed_seconds, cpu_seconds and plateau_scale finite and >= 0; best_mae_r, plateau_best and
/// epoch_loss_sum finite; null means "keep the default". Throws std::invalid_argument naming
/// the key and the value.
void CheckTrainerStateJson(const nlohmann::json& j);

/// The model family a checked checkpoint holds: config.arch; "" when it records none (written
/// before configs had "arch": ogmm/family.hpp FamilyOfConfig says which family that is).
std::string CheckpointArch(const nlohmann::json& checkpoint);

}  // namespace regbench::ogmm
