#include "networks/checkpoint/checkpoint.hpp"

#include <gtest/gtest.h>

#include <stdlib.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "networks/net.hpp"
#include "networks/zoo.hpp"
#include "tests/testing/file_size_limit.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/kill_save.hpp"

namespace regbench::networks {
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

/// The value of checkpoint.json's "steps" in `ck`, loaded into a fresh net whose parameters are
/// compared with `a` (steps 1) and `b` (steps 2): the loaded weights must be the ones of the
/// steps the json says, all of them.
int LoadedSteps(const fs::path& ck, RegistrationNet& a, RegistrationNet& b) {
    torch::manual_seed(99);
    auto c = MakeNet("deepgmr-orig-xyz");
    const int steps = LoadCheckpoint(ck.string(), *c).at("steps").get<int>();
    RegistrationNet& want = steps == 1 ? a : b;
    const auto pw = want.named_parameters();
    for (const auto& item : c->named_parameters())
        EXPECT_TRUE(torch::equal(item.value(), pw[item.key()])) << item.key();
    return steps;
}

// Issue 55, item 2: saving removed the old folder before renaming the new one in, so a kill in
// between left only ck.tmp and no checkpoint. Expected, for a kill after every step of the save
// (REGBENCH_TEST_KILL_SAVE_AT, SIGKILL: no cleanup runs) of checkpoint B over checkpoint A:
// while B is being written (steps 1-4) A is what loads, once B is whole (the old folder moved
// aside, step 5, and later) B; ck itself loads whenever it exists, and when it does not (the
// kill between the two renames) the loader's error names the leftover; recovery leaves no ck.tmp or ck.old behind,
// and the next save works.
TEST(Checkpoint, AKillAtEveryStepOfASaveLeavesALoadableCheckpoint) {
    torch::set_num_threads(1);
    torch::manual_seed(1);
    auto a = MakeNet("deepgmr-orig-xyz");
    torch::manual_seed(2);
    auto b = MakeNet("deepgmr-orig-xyz");
    torch::optim::Adam opt(b->parameters(), torch::optim::AdamOptions(1e-3));
    for (int k = 1; k <= 7; ++k) {
        SCOPED_TRACE("killed after step " + std::to_string(k));
        const fs::path dir = TempDir("kill_" + std::to_string(k));
        const fs::path ck = dir / "ck";
        SaveCheckpoint(ck.string(), *a, {{"steps", 1}}, &opt);
        const int status = testing::RunSaveKilledAtStep(
            k, [&] { SaveCheckpoint(ck.string(), *b, {{"steps", 2}}, &opt); });
        ASSERT_EQ(testing::NotKilledBySigkill(status), "");
        const int expected = k <= 4 ? 1 : 2;
        if (fs::exists(ck)) {
            EXPECT_EQ(LoadedSteps(ck, *a, *b), expected);
        } else {
            EXPECT_EQ(k, 5);  // only between the two renames
            const std::string msg = ErrorOf([&] { ReadCheckpointJson(ck.string()); });
            EXPECT_NE(msg.find(ck.string() + ".tmp"), std::string::npos) << msg;
            EXPECT_NE(msg.find(ck.string() + ".old"), std::string::npos) << msg;
        }
        const std::string done = RecoverCheckpointFolder(ck.string());
        EXPECT_EQ(done.empty(), k == 7) << done;  // a finished save leaves nothing behind
        EXPECT_EQ(LoadedSteps(ck, *a, *b), expected);
        EXPECT_FALSE(fs::exists(dir / "ck.tmp"));
        EXPECT_FALSE(fs::exists(dir / "ck.old"));
        SaveCheckpoint(ck.string(), *b, {{"steps", 2}}, &opt);
        EXPECT_EQ(LoadedSteps(ck, *a, *b), 2);
        fs::remove_all(dir);
    }
}

// A first save killed before its folder was complete left ck.tmp alone: recovery removes it
// (nothing loadable was ever there) and says so; a complete one is renamed in.
TEST(Checkpoint, RecoveryOfAFirstSaveKeepsOnlyAWholeFolder) {
    torch::set_num_threads(1);
    auto net = MakeNet("deepgmr-orig-xyz");
    for (int k : {2, 4}) {
        SCOPED_TRACE("killed after step " + std::to_string(k));
        const fs::path dir = TempDir("first_" + std::to_string(k));
        const fs::path ck = dir / "ck";
        const int status = testing::RunSaveKilledAtStep(
            k, [&] { SaveCheckpoint(ck.string(), *net, {{"steps", 1}}); });
        ASSERT_EQ(testing::NotKilledBySigkill(status), "");
        EXPECT_FALSE(fs::exists(ck));
        EXPECT_TRUE(fs::exists(dir / "ck.tmp"));
        const std::string done = RecoverCheckpointFolder(ck.string());
        EXPECT_NE(done.find((dir / "ck.tmp").string()), std::string::npos) << done;
        EXPECT_EQ(fs::exists(ck), k == 4) << done;
        EXPECT_FALSE(fs::exists(dir / "ck.tmp"));
        fs::remove_all(dir);
    }
}

// Issue 55, item 1: `import-checkpoint --out . --force` emptied the current folder (the save
// removed DIR whole and wrote DIR + ".tmp"), `--out v1/` deleted v1 through "v1/.tmp". Expected:
// ".", "..", "a/." and "/" are refused naming the path; "v1/" is the folder v1 (its temporary
// v1.tmp beside it); a folder holding anything but a checkpoint's files is never replaced, and
// every file in it stays.
TEST(Checkpoint, SaveRefusesFoldersThatAreNotACheckpointOfTheirOwn) {
    torch::set_num_threads(1);
    const fs::path dir = TempDir("folders");
    auto net = MakeNet("deepgmr-orig-xyz");
    const std::vector<std::string> bads = {".",  "..", "./", (dir / ".").string(),
                                           (dir / "..").string(), "/", ""};
    for (const std::string& bad : bads) {
        const std::string msg = ErrorOf([&] { SaveCheckpoint(bad, *net, {}); });
        EXPECT_NE(msg.find("'" + bad + "'"), std::string::npos) << bad << ": " << msg;
    }
    // A folder of other files, and a training run folder: refused, kept.
    fs::create_directories(dir / "mine");
    std::ofstream(dir / "mine" / "keep") << "keep";
    fs::create_directories(dir / "run" / "last");
    std::ofstream(dir / "run" / "metrics.csv") << "epoch\n";
    for (const char* name : {"mine", "run"}) {
        const fs::path target = dir / name;
        const std::string msg = ErrorOf([&] { SaveCheckpoint(target.string() + "/", *net, {}); });
        EXPECT_NE(msg.find(target.string()), std::string::npos) << msg;
        EXPECT_NE(msg.find("not a regbench checkpoint folder"), std::string::npos) << msg;
    }
    EXPECT_EQ(testing::ReadBytes(dir / "mine" / "keep"), "keep");
    EXPECT_TRUE(fs::exists(dir / "run" / "metrics.csv"));
    EXPECT_TRUE(fs::exists(dir / "run" / "last"));
    // A trailing slash names the folder itself, new or replaced.
    SaveCheckpoint((dir / "v1/").string(), *net, {{"steps", 1}});
    SaveCheckpoint((dir / "v1//").string(), *net, {{"steps", 2}});
    EXPECT_EQ(ReadCheckpointJson((dir / "v1").string()).at("steps"), 2);
    EXPECT_FALSE(fs::exists(dir / "v1" / ".tmp"));
    EXPECT_FALSE(fs::exists(dir / "v1.tmp"));
    EXPECT_FALSE(fs::exists(dir / "v1.old"));
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench::networks
