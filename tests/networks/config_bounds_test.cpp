// Issue 55, item 5 (configs): sizes inferred from a file's tensor shapes or read from a
// checkpoint.json had no upper bound: a 993-byte REGTR file with d_embed 4096 allocated 1.9 GB,
// RIENet's dim 65536 (within the old bound of 2^16) asked for 103 GB, REGTR's layers and
// OMNet's iterations were unbounded. Expected: each refused before anything is built, naming
// the key (and, from a checkpoint, the file); the shipped models build as before.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "networks/checkpoint/authors_checkpoint.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/checkpoint/torch_save_reader.hpp"
#include "networks/family.hpp"
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
    // Each family's Validate (networks/families/<family>/net.cpp) declares the range; the
    // message is core/params.hpp's: the key, the bound and the value given.
    const std::vector<Case> cases = {
        {"regtr-small", {{"d_embed", 4096}}, "'d_embed' must be <= 1024, got 4096"},
        {"regtr-small", {{"num_encoder_layers", 1000}}, "'num_encoder_layers' must be <= 24"},
        {"regtr-small", {{"d_feedforward", 1 << 20}}, "'d_feedforward' must be <= 4096"},
        {"regtr-small", {{"r_p", -1.0}}, "'r_p' must be > 0.0, got -1.0"},
        {"rienet", {{"dim", 65536}}, "'dim' must be <= 256, got 65536"},
        {"rienet", {{"iterations", 1000}}, "'iterations' must be <= 32, got 1000"},
        {"omnet-small", {{"iterations", 1000}}, "'iterations' must be <= 32, got 1000"},
        {"omnet-small", {{"mask_delay", 33}}, "'mask_delay' must be <= 32, got 33"},
        {"ogmm-tiny", {{"emb_dims", 65536}}, "'emb_dims' must be <= 2048, got 65536"},
        {"ogmm-tiny", {{"gmm_iterations", 100000}}, "'gmm_iterations' must be <= 1000"},
        {"deepgmr-small", {{"clusters", 1 << 20}}, "'clusters' must be <= 1024"},
        {"deepgmr-orig", {{"d_model", 65536}}, "'d_model' must be <= 4096, got 65536"},
        {"rgm-small", {{"sinkhorn_iterations", 1 << 20}}, "'sinkhorn_iterations' must be <= 1000"},
        {"rgm-small", {{"k", 4096}}, "'k' must be <= 128, got 4096"},
        {"rgm-small", {{"label_dist", 0.0}}, "'label_dist' must be > 0.0, got 0.0"},
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
    const fs::path dir = testing::FreshTempDir("config_bounds");
    const fs::path ck = dir / "regtr";
    fs::copy(testing::ShippedModel("regtr"), ck);
    const fs::path json = ck / "checkpoint.json";
    nlohmann::json j = nlohmann::json::parse(testing::ReadBytes(json));
    j["config"]["d_embed"] = 4096;
    j["model_config"]["d_embed"] = 4096;
    std::ofstream(json, std::ios::trunc) << j.dump();
    const std::string e = ErrorOf([&] { LoadNetFromCheckpoint(ck.string()); });
    EXPECT_NE(e.find(json.string()), std::string::npos) << e;
    EXPECT_NE(e.find("'d_embed' must be <= 1024"), std::string::npos) << e;
    fs::remove_all(dir);
}

// What every family's config gets from its one declaration (networks/family_config.hpp), for
// each model of each family: the config a network reports parses back to the same JSON, an
// unknown key is refused by name, and another family's arch is refused.
TEST(ConfigBounds, EveryFamilysConfigRoundTripsAndRefusesUnknownKeysAndOtherArches) {
    for (const auto& f : Families()) {
        for (const auto& m : f.models) {
            SCOPED_TRACE(f.arch + " " + m);
            nlohmann::json config = f.named_config(m);
            config.erase("train");
            const nlohmann::json reported = f.build(config)->Config();
            EXPECT_EQ(f.build(reported)->Config(), reported);
            nlohmann::json unknown = config;
            unknown["no_such_key"] = 1;
            EXPECT_NE(ErrorOf([&] { f.check_config(unknown); }).find("'no_such_key'"),
                      std::string::npos);
            nlohmann::json other = config;
            other["arch"] = f.arch + "-other";
            EXPECT_NE(ErrorOf([&] { f.check_config(other); }), "");
        }
    }
}

// Every declared range is stated where the docs are: each config key of each family has a doc
// ending in its range (core/params.hpp RangeText), so `train --list-models` prints it.
TEST(ConfigBounds, EveryNumericConfigKeyDocumentsItsRange) {
    for (const auto& f : Families()) {
        const nlohmann::json config = f.named_config(f.models.front());
        for (const auto& [key, doc] : f.config_docs) {
            const auto it = config.find(key);
            if (it != config.end() && !it->is_number()) continue;
            EXPECT_NE(doc.find("; range "), std::string::npos)
                << f.arch << " " << key << ": " << doc;
        }
    }
}

// Sizes inferred from an authors' file's tensor shapes go through the same ranges, before any
// network is built: a few-KB state dict whose shapes declare RIENet's dim 65536 (103 GB) or 40
// OMNet iterations is refused naming the file and the key.
TEST(ConfigBounds, AnAuthorsFileWhoseShapesGiveASizeBeyondItsRangeIsRefused) {
    const fs::path dir = testing::FreshTempDir("config_bounds_authors");
    struct Case {
        const char* from;
        StateDict sd;
        const char* why;
    };
    const auto zeros = [](std::vector<int64_t> shape) { return torch::zeros(shape); };
    StateDict omnet = {{"encoder.0.conv_block1.0.weight", zeros({64, 3, 1})}};
    for (int i = 1; i < 40; ++i) {
        omnet.emplace_back("encoder." + std::to_string(i) + ".conv_block1.0.weight", zeros({1}));
    }
    const std::vector<Case> cases = {
        {"rienet",
         {{"emb_nn.model.conv5.weight", zeros({256, 1, 1, 1})},
          {"forwards.weight_function.model1.0.weight", zeros({65536, 1, 1, 1})}},
         "'dim' must be <= 256, got 65536"},
        {"omnet", omnet, "'iterations' must be <= 32, got 40"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.from);
        const fs::path pth = dir / (std::string(c.from) + ".pth");
        std::ofstream(pth, std::ios::binary) << WriteTorchSaveZip(c.sd);
        ImportOptions options;
        options.from = c.from;
        const std::string e = ErrorOf(
            [&] { ImportAuthorsCheckpoint(pth.string(), (dir / "out").string(), options); });
        EXPECT_NE(e.find(pth.string()), std::string::npos) << e;
        EXPECT_NE(e.find(c.why), std::string::npos) << e;
        EXPECT_FALSE(fs::exists(dir / "out"));
    }
    fs::remove_all(dir);
}

// The move of the configs onto the Fields/Validate binding changed no checkpoint: every shipped
// checkpoint.json (data/models/**) builds, and its network's config is its model_config byte
// for byte; the six shipped models, loaded and saved again, write the same checkpoint.json
// (apart from the build's version and git sha) and the same weights.
TEST(ConfigBounds, ShippedCheckpointsLoadAndSaveUnchanged) {
    const char* src = std::getenv("REGBENCH_SOURCE_DIR");
    ASSERT_NE(src, nullptr);
    const fs::path models = fs::path(src) / "data" / "models";
    int checked = 0;
    for (const auto& entry : fs::recursive_directory_iterator(models)) {
        if (entry.path().filename() != "checkpoint.json") continue;
        SCOPED_TRACE(entry.path().string());
        const nlohmann::json j = nlohmann::json::parse(testing::ReadBytes(entry.path()));
        nlohmann::json config = j.contains("config") ? j.at("config") : j.at("model_config");
        config.erase("train");
        const NetworkFamily& family = FamilyOfConfig(config);
        EXPECT_NO_THROW(family.check_config(config));
        EXPECT_EQ(family.build(config)->Config().dump(), j.at("model_config").dump());
        ++checked;
    }
    EXPECT_GE(checked, 60);  // 67 when this was written
    const fs::path dir = testing::FreshTempDir("config_bounds_resave");
    for (const char* shipped : {"ogmm", "deepgmr", "omnet", "rienet", "rgm", "regtr"}) {
        SCOPED_TRACE(shipped);
        const fs::path from = models / shipped;
        nlohmann::json before = nlohmann::json::parse(testing::ReadBytes(from / "checkpoint.json"));
        const auto net = LoadNetFromCheckpoint(from.string());
        nlohmann::json meta = before;
        for (const char* written : {"format", "format_version", "model_config", "regbench_version",
                                    "git_sha", "weights", "weights_bytes"}) {
            meta.erase(written);
        }
        const fs::path to = dir / shipped;
        SaveCheckpoint(to.string(), *net, meta);
        nlohmann::json after = nlohmann::json::parse(testing::ReadBytes(to / "checkpoint.json"));
        for (const char* build : {"regbench_version", "git_sha"}) after[build] = before[build];
        EXPECT_EQ(after.dump(2), before.dump(2));
        EXPECT_TRUE(testing::ReadBytes(to / "weights.pt") ==
                    testing::ReadBytes(from / "weights.pt"));
    }
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench::networks
