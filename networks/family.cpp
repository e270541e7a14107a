#include "networks/family.hpp"

#include <mutex>
#include <stdexcept>

namespace regbench::networks {

// The tree's families, each declared in its own folder (networks/families/<family>/family.cpp)
// and listed once, on one line, in networks/families/families.def.
#define REGBENCH_FAMILY(function) NetworkFamily function();
#include "networks/families/families.def"
#undef REGBENCH_FAMILY

namespace {

/// Checkpoints written before configs recorded "arch" hold this family's networks.
constexpr char kArchBeforeArchKey[] = "ogmm";

std::vector<NetworkFamily> TreeFamilies() {
    return {
#define REGBENCH_FAMILY(function) function(),
#include "networks/families/families.def"
#undef REGBENCH_FAMILY
    };
}

std::vector<NetworkFamily>& Registry() {
    static std::vector<NetworkFamily> families = TreeFamilies();
    return families;
}

std::string Join(const std::vector<std::string>& names) {
    std::string out;
    for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
    return out;
}

void CheckUnique(const NetworkFamily& family) {
    for (const auto& f : Registry()) {
        if (f.arch == family.arch) {
            throw std::invalid_argument("network family '" + family.arch + "' is registered");
        }
        for (const auto& model : family.models) {
            for (const auto& taken : f.models) {
                if (model == taken) {
                    throw std::invalid_argument("model '" + model + "' of family '" + family.arch +
                                                "' is a model of '" + f.arch + "'");
                }
            }
        }
        for (const auto& method : family.methods) {
            for (const auto& taken : f.methods) {
                if (method.name == taken.name) {
                    throw std::invalid_argument("method '" + method.name + "' of family '" +
                                                family.arch + "' is a method of '" + f.arch + "'");
                }
            }
        }
    }
}

}  // namespace

const std::vector<NetworkFamily>& Families() { return Registry(); }

void RegisterFamily(NetworkFamily family) {
    static std::mutex mutex;
    const std::lock_guard<std::mutex> lock(mutex);
    if (family.arch.empty() || !family.named_config || !family.check_config || !family.build ||
        !family.forward_cost) {
        throw std::invalid_argument("network family '" + family.arch +
                                    "': arch, named_config, check_config, build and "
                                    "forward_cost are required");
    }
    CheckUnique(family);
    Registry().push_back(std::move(family));
}

const NetworkFamily& FindFamily(const std::string& arch) {
    std::vector<std::string> known;
    for (const auto& f : Families()) {
        if (f.arch == arch) return f;
        known.push_back(f.arch);
    }
    throw std::invalid_argument("unknown network family (arch) '" + arch +
                                "' (known: " + Join(known) + ")");
}

const NetworkFamily& FamilyOfConfig(const nlohmann::json& config) {
    if (!config.is_object()) {
        throw std::invalid_argument("model config is not an object: " + config.dump());
    }
    if (!config.contains("arch")) return FindFamily(kArchBeforeArchKey);
    if (!config.at("arch").is_string()) {
        throw std::invalid_argument("model config: \"arch\" must be a string, got " +
                                    config.at("arch").dump());
    }
    return FindFamily(config.at("arch").get<std::string>());
}

const NetworkFamily& FamilyOfModel(const std::string& model) {
    std::vector<std::string> known;
    for (const auto& f : Families()) {
        for (const auto& m : f.models) {
            if (m == model) return f;
            known.push_back(m);
        }
    }
    throw std::invalid_argument("unknown model '" + model + "' (known: " + Join(known) + ")");
}

std::vector<std::string> AuthorsFormats() {
    std::vector<std::string> out;
    for (const auto& f : Families()) {
        if (f.authors) out.push_back(f.arch);
    }
    return out;
}

}  // namespace regbench::networks
