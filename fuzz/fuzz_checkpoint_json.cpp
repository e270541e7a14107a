// libFuzzer target: the checkpoint.json reader (ParseCheckpointJson: depth-limited parse, format,
// format_version, weights name and size, model_config, config.arch, every trainer counter), the
// torch-free part of every checkpoint load (train --resume, the learned methods' checkpoint
// check), and the weights file check (CheckWeightsBytes) on the same bytes taken as a weights
// file, against the parsed checkpoint or a valid one recording their size. A refusal is a
// std::runtime_error / std::invalid_argument naming the file; anything else is a finding.
#include <algorithm>
#include <cstdint>
#include <exception>
#include <string>
#include <string_view>

#include "networks/checkpoint/checkpoint_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    nlohmann::json checkpoint = {{"format", "regbench-checkpoint"},
                                 {"format_version", 1},
                                 {"model_config", nlohmann::json::object()},
                                 {"weights", "weights.pt"},
                                 {"weights_bytes", size}};
    try {
        const nlohmann::json j = regbench::networks::ParseCheckpointJson(text, "fuzz/checkpoint.json");
        (void)regbench::networks::CheckpointArch(j);
        (void)j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
        checkpoint = j;
    } catch (const std::runtime_error&) {
    } catch (const std::invalid_argument&) {
    }
    const std::string_view bytes(text);
    const std::size_t tail = std::min(bytes.size(), regbench::networks::kWeightsTailBytes);
    try {
        regbench::networks::CheckWeightsBytes(bytes.substr(0, 4), bytes.substr(bytes.size() - tail),
                                          size, checkpoint, "fuzz/weights.pt");
    } catch (const std::runtime_error&) {
    }
    return 0;
}
