// `regbench methods`: every registered method with its parameters and defaults (--json adds
// each method's parameter schema, for editors that validate configs).
#include <iostream>

#include "app/commands.hpp"
#include "runners/registry.hpp"

namespace regbench::app {

namespace {

void SetupMethodsCommand(CLI::App* cmd) {
    auto* json_out = cmd->add_flag("--json", "Print as JSON instead of text");
    cmd->callback([json_out] {
        if (*json_out) {
            nlohmann::json out = nlohmann::json::array();
            for (const auto& m : AllMethods()) {
                out.push_back({{"name", m.name},
                               {"summary", m.summary},
                               {"defaults", m.defaults},
                               {"param_docs", m.param_docs},
                               {"schema", m.schema}});
            }
            std::cout << out.dump(2) << "\n";
            return;
        }
        for (const auto& m : AllMethods()) {
            std::cout << m.name << "  -  " << m.summary << "\n";
            for (const auto& item : m.defaults.items()) {
                const auto doc = m.param_docs.find(item.key());
                std::cout << "    " << item.key() << " = " << item.value().dump();
                if (doc != m.param_docs.end()) std::cout << "    # " << doc->second;
                std::cout << "\n";
            }
        }
    });
}

[[maybe_unused]] const bool kMethodsRegistered = RegisterCommand(
    {"methods", "List registered methods, their parameters and defaults", SetupMethodsCommand});
}  // namespace

}  // namespace regbench::app
