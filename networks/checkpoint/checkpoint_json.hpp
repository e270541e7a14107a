#pragma once
// checkpoint.json without LibTorch: parsing and every check of its contents, so the reader can
// be fuzzed in the sanitizer build (which has no LibTorch; fuzz/fuzz_checkpoint_json.cpp).
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace regbench::networks {

/// Parses `text` (the bytes of checkpoint.json at `path`) depth-limited and checks it: a JSON
/// object with "format" = regbench-checkpoint and a "model_config" object; "format_version",
/// when present, 1 (the one this regbench writes and reads); "weights", when present, the
/// weights file this regbench reads ("weights.pt": never an absolute path, a path with "..",
/// or another file); "weights_bytes", when present, a whole number >= 1; "config", when
/// present, an object whose "arch" (when present) is a string; "trainer", when present, passes
/// CheckTrainerStateJson. Throws std::runtime_error naming `path` and the key.
nlohmann::json ParseCheckpointJson(const std::string& text, const std::string& path);

/// The weights file of a checked checkpoint, as its writer (SaveCheckpoint: torch's zip archive)
/// leaves it: `size` > 0 bytes, equal to "weights_bytes" when the checkpoint records it; a zip
/// archive (local header "PK\3\4" at the start of `head`, an end-of-central-directory record
/// in `tail`, the last bytes of the file, whose central directory lies inside the file). A
/// missing, empty, truncated or garbage file is refused here, before any run, instead of
/// failing every row. Throws std::runtime_error naming `path`.
void CheckWeightsBytes(std::string_view head, std::string_view tail, std::uint64_t size,
                       const nlohmann::json& checkpoint, const std::string& path);

/// How many bytes of the file's end CheckWeightsBytes needs: the 22-byte record after at most a
/// 65,535-byte archive comment.
inline constexpr std::size_t kWeightsTailBytes = 22 + 65535;

/// The trainer counters as written: "step" present; step, planned_steps, pairs_seen,
/// plateau_bad and epoch_loss_steps whole numbers in [0, 2^53] (plateau_bad <= 1e9); lr,
/// elapsed_seconds, cpu_seconds and plateau_scale finite and >= 0; best_mae_r, plateau_best and
/// epoch_loss_sum finite; null means "keep the default". Throws std::invalid_argument naming
/// the key and the value.
void CheckTrainerStateJson(const nlohmann::json& j);

/// The model family a checked checkpoint holds: config.arch; "" when it records none (written
/// before configs had "arch": networks/family.hpp FamilyOfConfig says which family that is).
std::string CheckpointArch(const nlohmann::json& checkpoint);

}  // namespace regbench::networks
