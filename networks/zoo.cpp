#include "networks/zoo.hpp"

#include <stdexcept>

#include "networks/family.hpp"

namespace regbench::networks {

std::vector<std::string> ModelNames() {
    std::vector<std::string> names;
    for (const auto& f : Families()) names.insert(names.end(), f.models.begin(), f.models.end());
    return names;
}

nlohmann::json NamedConfig(const std::string& name) {
    return FamilyOfModel(name).named_config(name);
}

std::shared_ptr<RegistrationNet> MakeNetFromConfig(const nlohmann::json& config) {
    if (!config.is_object() || !config.contains("arch")) {
        throw std::invalid_argument("model config has no \"arch\": " + config.dump());
    }
    nlohmann::json net = config;
    net.erase("train");
    const NetworkFamily& family = FamilyOfConfig(net);
    family.check_config(net);
    return family.build(net);
}

nlohmann::json ResolveConfig(const std::string& name, const nlohmann::json& overrides) {
    nlohmann::json config = NamedConfig(name);
    if (!overrides.is_null()) config.merge_patch(overrides);
    return config;
}

std::shared_ptr<RegistrationNet> MakeNet(const std::string& name, const nlohmann::json& overrides) {
    return MakeNetFromConfig(ResolveConfig(name, overrides));
}

}  // namespace regbench::networks
