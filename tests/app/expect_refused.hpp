#pragma once
// Helpers of the output-rule tests (tests/app/cli_output_rule_test.cpp and the checkpoint
// writers in cli_checkpoint_refusal_test.cpp): a refusal must leave every file as it was.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/testing/cli.hpp"
#include "tests/testing/files.hpp"

namespace regbench::testing {

inline void Put(const std::filesystem::path& p, const std::string& text) {
    std::ofstream(p, std::ios::binary) << text;
}

/// `args` exits 1 (not a usage error, not a signal), names `name` and says `why`; every file in
/// `kept` has the bytes it had before.
inline void ExpectRefused(const std::string& args, const std::string& name,
                          const std::string& why, const std::vector<std::string>& kept) {
    SCOPED_TRACE(args);
    std::vector<std::string> before;
    for (const auto& k : kept) before.push_back(ReadBytes(k));
    const CliResult r = RunCli(args);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(name), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(why), std::string::npos) << r.output;
    for (std::size_t i = 0; i < kept.size(); ++i) {
        EXPECT_TRUE(std::filesystem::exists(kept[i])) << kept[i];
        EXPECT_EQ(ReadBytes(kept[i]), before[i]) << kept[i];
    }
}

}  // namespace regbench::testing
