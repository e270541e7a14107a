#pragma once
// The model zoo: named configurations of every learned network and one factory for all of them.
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace regbench::networks {

class RegistrationNet;  // networks/net.hpp; declared only, so this header is free of LibTorch's

/// Names MakeNet knows, in display order.
std::vector<std::string> ModelNames();
/// Full configuration of a named model: the network fields (with "arch") plus a "train" object
/// with the training recipe (see TrainConfig). Throws std::invalid_argument for an unknown name,
/// listing the known ones.
nlohmann::json NamedConfig(const std::string& name);
/// Builds a network from a full configuration (its "train" object, if any, is ignored).
std::shared_ptr<RegistrationNet> MakeNetFromConfig(const nlohmann::json& config);
/// NamedConfig(name) with `overrides` merged in (JSON merge patch), built.
std::shared_ptr<RegistrationNet> MakeNet(
    const std::string& name, const nlohmann::json& overrides = nlohmann::json::object());
/// NamedConfig(name) merge-patched with `overrides` (what MakeNet builds).
nlohmann::json ResolveConfig(const std::string& name, const nlohmann::json& overrides);

}  // namespace regbench::networks
