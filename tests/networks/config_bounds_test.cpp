// Issue 55, item 5 (configs): sizes inferred from a file's tensor shapes or read from a
// checkpoint.json had no upper bound: a 993-byte REGTR file with d_embed 4096 allocated 1.9 GB,
// RIENet's dim 65536 (within the old bound of 2^16) asked for 103 GB, REGTR's layers and
// OMNet's iterations were unbounded. Expected: each refused before anything is built, naming
// the key (and, from a checkpoint, the file); the shipped models build as before.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "networks/checkpoint/checkpoint.hpp"
#include "networks/net.hpp"
#include "networks/zoo.hpp"
#include "tests/testing/files.hpp"

namespace regbench::networks {
namespace {
namespace fs = std::filesystem;

using testing::ErrorOf;

TEST(ConfigBounds, SizesBeyondTheFamilysRangeAreRefusedNamingTheKey) {
    struct Case {
        const char* model;
        nlohmann::json overrides;
        const char* why;
    };
    const std::vector<Case> cases = {
        {"regtr-small", {{"d_embed", 4096}}, "d_embed <= 1024"},
        {"regtr-small", {{"num_encoder_layers", 1000}}, "num_encoder_layers <= 24"},
        {"regtr-small", {{"d_feedforward", 1 << 20}}, "d_feedforward <= 4096"},
        {"rienet", {{"dim", 65536}}, "dim must be <= 256, got 65536"},
        {"rienet", {{"iterations", 1000}}, "iterations must be <= 32, got 1000"},
        {"omnet-small", {{"iterations", 1000}}, "iterations and mask_delay must be <= 32"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(std::string(c.model) + " " + c.overrides.dump());
        const std::string e = ErrorOf([&] { MakeNet(c.model, c.overrides); });
        EXPECT_NE(e.find(c.why), std::string::npos) << e;
    }
    // At the bounds' other side, the authors' sizes: built.
    EXPECT_EQ(ErrorOf([] { MakeNet("rienet", {{"dim", 16}}); }), "");
}

TEST(ConfigBounds, ACheckpointWithASizeBeyondItsRangeIsRefusedNamingTheFile) {
    const char* src = std::getenv("REGBENCH_SOURCE_DIR");
    ASSERT_NE(src, nullptr);
    const fs::path dir = testing::FreshTempDir("config_bounds");
    const fs::path ck = dir / "regtr";
    fs::copy(fs::path(src) / "data" / "models" / "regtr", ck);
    const fs::path json = ck / "checkpoint.json";
    nlohmann::json j = nlohmann::json::parse(testing::ReadBytes(json));
    j["config"]["d_embed"] = 4096;
    j["model_config"]["d_embed"] = 4096;
    std::ofstream(json, std::ios::trunc) << j.dump();
    const std::string e = ErrorOf([&] { LoadNetFromCheckpoint(ck.string()); });
    EXPECT_NE(e.find(json.string()), std::string::npos) << e;
    EXPECT_NE(e.find("d_embed <= 1024"), std::string::npos) << e;
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench::networks
