#pragma once
// The `--params` option shared by run, merge, align and score: a JSON object of method
// parameters given on the command line; with `--methods`, the method list of run and merge.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/json_limits.hpp"
#include "runners/runner.hpp"

namespace regbench::app {

/// Parses the text of `--params`; an empty text (option not given) is an empty object.
/// Malformed JSON is refused naming the option.
inline nlohmann::json ParseParamsOption(const std::string& text) {
    if (text.empty()) return nlohmann::json::object();
    try {
        return ParseJsonBounded(text, "--params");
    } catch (const nlohmann::json::exception& e) {
        throw CLI::ValidationError(std::string("--params is not valid JSON: ") + e.what());
    } catch (const std::runtime_error& e) {
        // The depth limit (64 levels): a usage error like any other bad --params, not exit 1.
        throw CLI::ValidationError(e.what());
    }
}

/// `--methods` (required) and `--params` of run, and of merge (which must name what the shards
/// ran): one parse for both, at callback time.
struct MethodArgs {
    std::string methods, params;

    void Add(CLI::App* cmd, const std::string& methods_help, const std::string& params_help) {
        cmd->add_option("--methods", methods, methods_help)->required();
        cmd->add_option("--params", params, params_help);
    }
    /// The methods with their full parameters; throws naming a bad name, key or value.
    std::vector<MethodSpec> Specs() const {
        return ParseMethodSpecs(methods, ParseParamsOption(params));
    }
};

}  // namespace regbench::app
