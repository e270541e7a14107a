#pragma once
// The `--params` option shared by run, merge, align and score: a JSON object of method
// parameters given on the command line; with `--methods`, the method list of run and merge.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/cli_numbers.hpp"
#include "core/json_limits.hpp"
#include "core/metrics.hpp"
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

/// Runs `parse` (reading flag values, before any work); a std::invalid_argument it throws (an
/// unknown method or protocol name, a bad parameter) becomes a usage error (exit 2).
template <class Parse>
auto AsUsageError(Parse parse) -> decltype(parse()) {
    try {
        return parse();
    } catch (const std::invalid_argument& e) {
        throw CLI::ValidationError(e.what());
    }
}

/// A validator that accepts the texts `parse` accepts (ParseProtocol, ParsePairing, ...) and
/// refuses the others with `parse`'s message (naming the known names, with a "did you mean").
template <class Parse>
CLI::Validator ParsedBy(Parse parse, const std::string& name) {
    return CLI::Validator(
        [parse](std::string& text) -> std::string {
            try {
                parse(text);
                return "";
            } catch (const std::invalid_argument& e) {
                return e.what();
            }
        },
        name);
}

/// `--ccd-clip` and `--inlier-threshold` of run and score: what the cloud metrics are measured
/// with (core/metrics.hpp MetricOptions; docs/metrics.md).
inline void AddMetricOptions(CLI::App* cmd, MetricOptions* o) {
    cmd->add_option("--ccd-clip", o->ccd_clip,
                    "CCD clip distance in cloud units (default: the paper code's 0.1, for objects "
                    "in the unit sphere, times the pair file's scale from generate --scale; a "
                    "warning says when the clouds' size makes it meaningless)")
        ->check(PositiveReal())
        ->capture_default_str();
    cmd->add_option("--inlier-threshold", o->inlier_threshold,
                    "Also compute Open3D's evaluate_registration at this max correspondence "
                    "distance (cloud units): metrics fitness and inlier_rmse; 0 = not computed")
        ->check(NonNegativeReal())
        ->capture_default_str();
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
        return AsUsageError([&] { return ParseMethodSpecs(methods, ParseParamsOption(params)); });
    }
};

}  // namespace regbench::app
