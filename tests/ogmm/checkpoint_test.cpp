#include "ogmm/checkpoint.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "ogmm/net.hpp"
#include "ogmm/zoo.hpp"
#include "tests/testing/file_size_limit.hpp"
#include "tests/testing/files.hpp"

namespace regbench::ogmm {
namespace {
namespace fs = std::filesystem;

using testing::ErrorOf;

fs::path TempDir(const std::string& name) { return testing::FreshTempDir("ckpt_" + name); }

/// A fresh temporary folder `name` holding the checkpoint `ck` of a default deepgmr-orig-xyz
/// net, for the tests that damage or mismatch it.
struct SavedCheckpoint {
    fs::path dir;  ///< the temporary folder (removed by the test)
    fs::path ck;   ///< dir / "ck"
    std::shared_ptr<RegistrationNet> net;
};
SavedCheckpoint SaveDefault(const std::string& name) {
    SavedCheckpoint s{TempDir(name), {}, MakeNet("deepgmr-orig-xyz")};
    s.ck = s.dir / "ck";
    SaveCheckpoint(s.ck.string(), *s.net, {});
    return s;
}

TEST(Checkpoint, RoundTripIsBitExact) {
    torch::set_num_threads(1);
    const fs::path dir = TempDir("roundtrip");
    torch::manual_seed(11);
    auto a = MakeNet("deepgmr-orig-xyz");
    // Give the BN running statistics non-default values so buffers are checked too.
    for (auto& b : a->buffers()) {
        if (b.is_floating_point()) b.uniform_(0.5, 2.0);
    }
    SaveCheckpoint((dir / "ck").string(), *a, {{"model", "deepgmr-orig-xyz"}, {"steps", 3}});
    torch::manual_seed(12);  // different initial weights
    auto b = MakeNet("deepgmr-orig-xyz");
    const nlohmann::json j = LoadCheckpoint((dir / "ck").string(), *b);
    EXPECT_EQ(j.at("steps"), 3);
    EXPECT_EQ(j.at("git_sha"), BuildGitSha());
    const auto pa = a->named_parameters();
    const auto pb = b->named_parameters();
    ASSERT_EQ(pa.size(), pb.size());
    for (const auto& item : pa)
        EXPECT_TRUE(torch::equal(item.value(), pb[item.key()])) << item.key();
    const auto ba = a->named_buffers();
    const auto bb = b->named_buffers();
    for (const auto& item : ba)
        EXPECT_TRUE(torch::equal(item.value(), bb[item.key()])) << item.key();
    // A fresh net from the checkpoint alone gives the same net.
    auto c = LoadNetFromCheckpoint((dir / "ck").string());
    for (const auto& item : c->named_parameters()) {
        EXPECT_TRUE(torch::equal(item.value(), pa[item.key()])) << item.key();
    }
    fs::remove_all(dir);
}

TEST(Checkpoint, RefusesAnotherConfigNamingTheFile) {
    const SavedCheckpoint saved = SaveDefault("mismatch");
    auto b = MakeNet("deepgmr-orig-xyz", {{"clusters", 8}});
    const std::string msg = ErrorOf([&] { LoadCheckpoint(saved.ck.string(), *b); });
    EXPECT_NE(msg.find((saved.ck / "checkpoint.json").string()), std::string::npos) << msg;
    fs::remove_all(saved.dir);
}

TEST(Checkpoint, LoadsAClusteredAttentionCheckpointWithFullAttention) {
    // Full and clustered attention have the same modules (only the keys differ), so the
    // weights of one load into the other, unchanged; a key that changes the parameters is
    // refused.
    torch::set_num_threads(1);
    const fs::path dir = TempDir("attention");
    torch::manual_seed(3);
    auto clustered = MakeNet("ogmm-tiny");
    const nlohmann::json config = NamedConfig("ogmm-tiny");
    ASSERT_EQ(config.at("attention"), "clustered");
    SaveCheckpoint((dir / "ck").string(), *clustered, {{"config", config}});
    const auto full = LoadNetFromCheckpoint((dir / "ck").string(), {{"attention", "full"}});
    EXPECT_EQ(full->Config().at("attention"), "full");
    const auto pa = clustered->named_parameters();
    for (const auto& item : full->named_parameters())
        EXPECT_TRUE(torch::equal(item.value(), pa[item.key()])) << item.key();
    EXPECT_EQ(CheckpointNetConfig((dir / "ck").string(), {{"attention", "full"}}).at("attention"),
              "full");
    EXPECT_EQ(CheckpointNetConfig((dir / "ck").string()).at("attention"), "clustered");
    const std::string msg = ErrorOf([&] {
        LoadNetFromCheckpoint((dir / "ck").string(), {{"emb_dims", 8}});
    });
    EXPECT_NE(msg.find("'emb_dims' changes the network's parameters"), std::string::npos) << msg;
    fs::remove_all(dir);
}

TEST(Checkpoint, RefusesCorruptWeightsNamingTheFile) {
    const SavedCheckpoint saved = SaveDefault("corrupt");
    const fs::path weights = saved.ck / "weights.pt";
    const auto size = fs::file_size(weights);
    fs::resize_file(weights, size / 2);  // truncated write
    const std::string msg = ErrorOf([&] { LoadCheckpoint(saved.ck.string(), *saved.net); });
    EXPECT_NE(msg.find(weights.string()), std::string::npos) << msg;
    fs::remove_all(saved.dir);
}

TEST(Checkpoint, RefusesCorruptJsonNamingTheFile) {
    const SavedCheckpoint saved = SaveDefault("json");
    const fs::path json = saved.ck / "checkpoint.json";
    std::ofstream(json) << "{\"format\": \"regbench-checkpoint\", ";
    const std::string msg = ErrorOf([&] { LoadNetFromCheckpoint(saved.ck.string()); });
    EXPECT_NE(msg.find(json.string()), std::string::npos) << msg;
    const std::string missing =
        ErrorOf([&] { LoadNetFromCheckpoint((saved.dir / "nowhere").string()); });
    EXPECT_NE(missing.find("nowhere"), std::string::npos) << missing;
    fs::remove_all(saved.dir);
}

// Issue 27: a full disk (here a 4 KB file-size limit; the weights alone are far bigger) made
// torch's writer throw a c10::Error with a stack dump and left `ck.tmp/` behind. Expected: a
// runtime_error naming the checkpoint, no `ck.tmp`, and no `ck` (nothing was saved before).
TEST(Checkpoint, SaveOnAFullDiskGivesAMessageAndLeavesNoTemporaryFolder) {
    torch::set_num_threads(1);
    const fs::path dir = TempDir("full_disk");
    const fs::path ck = dir / "ck";
    auto net = MakeNet("deepgmr-orig-xyz");
    const int status = testing::RunUnderFileSizeLimit<std::runtime_error>(
        4096, "cannot save checkpoint " + ck.string(),
        [&] { SaveCheckpoint(ck.string(), *net, {}); });
    ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
    EXPECT_EQ(WEXITSTATUS(status), 3);
    EXPECT_FALSE(fs::exists(dir / "ck.tmp"));
    EXPECT_FALSE(fs::exists(ck));
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench::ogmm
