#include "runners/registry.hpp"

#include <stdexcept>

#include "baselines/filterreg.hpp"
#include "baselines/identity.hpp"

namespace regbench {

const std::vector<MethodInfo>& AllMethods() {
    static const std::vector<MethodInfo> methods = {
        IdentityMethodInfo(),
        FilterRegMethodInfo(),
    };
    return methods;
}

const MethodInfo& FindMethod(const std::string& name) {
    for (const auto& m : AllMethods()) {
        if (m.name == name) return m;
    }
    std::string known;
    for (const auto& m : AllMethods()) known += (known.empty() ? "" : ", ") + m.name;
    throw std::invalid_argument("unknown method '" + name + "' (known: " + known + ")");
}

std::unique_ptr<RegistrationMethod> CreateMethod(const std::string& name,
                                                 const nlohmann::json& params) {
    return FindMethod(name).create(params.is_null() ? nlohmann::json::object() : params);
}

}  // namespace regbench
