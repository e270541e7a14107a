#pragma once
// The `--params` option shared by run, merge, align and score: a JSON object of method
// parameters given on the command line.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "core/json_limits.hpp"

namespace regbench::app {

/// Parses the text of `--params`; an empty text (option not given) is an empty object.
/// Malformed JSON is refused naming the option.
inline nlohmann::json ParseParamsOption(const std::string& text) {
    if (text.empty()) return nlohmann::json::object();
    try {
        return ParseJsonBounded(text, "--params");
    } catch (const nlohmann::json::exception& e) {
        throw CLI::ValidationError(std::string("--params is not valid JSON: ") + e.what());
    }
}

}  // namespace regbench::app
