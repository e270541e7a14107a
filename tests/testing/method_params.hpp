#pragma once
// Parameter-rejection checks shared by the method tests (needs runners/, so only test folders
// that link regbench_runners include it).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "runners/registry.hpp"

namespace regbench::testing {

/// Creating `method` with `params` must throw std::invalid_argument whose message contains
/// `needle` (the parameter's name, quoted or not as the caller wants).
inline void ExpectRejected(const std::string& method, const nlohmann::json& params,
                           const std::string& needle) {
    try {
        CreateMethod(method, params);
        ADD_FAILURE() << method << " accepted " << params.dump();
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
}

/// Creating `method` with any one of the values in `bad` must throw std::invalid_argument
/// naming the parameter in quotes. `bad` maps each parameter to the values to try, e.g.
/// {"w": [1.0, -0.1]}: one CreateMethod call per value, with only that parameter set; a failure
/// names the method and the parameters.
inline void ExpectEachRejected(const std::string& method, const nlohmann::json& bad) {
    for (const auto& item : bad.items()) {
        for (const nlohmann::json& value : item.value()) {
            ExpectRejected(method, {{item.key(), value}}, "'" + item.key() + "'");
        }
    }
}

}  // namespace regbench::testing
