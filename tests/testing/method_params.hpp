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
inline void ExpectRejected(const std::string& method,
                           const nlohmann::json& params,
                           const std::string& needle) {
    try {
        CreateMethod(method, params);
        ADD_FAILURE() << method << " accepted " << params.dump();
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
}

}  // namespace regbench::testing
