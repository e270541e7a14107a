// libFuzzer target: the checkpoint.json reader (ParseCheckpointJson: depth-limited parse, format
// and model_config, config.arch, every trainer counter), the torch-free part of every checkpoint
// load (train --resume, the learned methods' checkpoint check). A refusal is a
// std::runtime_error / std::invalid_argument naming the file; anything else is a finding.
#include <cstdint>
#include <exception>
#include <string>

#include "ogmm/checkpoint_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const nlohmann::json j = regbench::ogmm::ParseCheckpointJson(text, "fuzz/checkpoint.json");
        (void)regbench::ogmm::CheckpointArch(j);
        (void)j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    } catch (const std::runtime_error&) {
    } catch (const std::invalid_argument&) {
    }
    return 0;
}
