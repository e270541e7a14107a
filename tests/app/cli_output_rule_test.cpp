// The one output rule (docs/usage.md, "Outputs"; issue 44 group 1), writer by writer: an
// existing output is refused unless --force (or --resume), an output equal to or inside an input
// is refused, a symbolic link is never written through, and OUT, OUT.part and OUT.lock share one
// lock. Each refusal must leave every file as it was (the expected bytes are the ones written
// here).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/testing/cli.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::RunCli;

void Put(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

class CliOutputRule : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = testing::FreshTempDir("output_rule");
        pairs_ = (dir_ / "p.h5").string();
        ASSERT_EQ(RunCli("generate --protocol partial --dataset procedural --split test --pairs 2 "
                         "--seed 1 --points 64 --out " +
                         pairs_)
                      .exit_code,
                  0);
        rows_ = (dir_ / "r.jsonl").string();
        ASSERT_EQ(
            RunCli("run --pairs " + pairs_ + " --methods identity -q --out " + rows_).exit_code, 0);
        xyz_ = (dir_ / "xyz").string();
        ASSERT_EQ(RunCli("export " + pairs_ + " --out " + xyz_).exit_code, 0);
    }
    void TearDown() override { fs::remove_all(dir_); }

    /// `args` exits 1 (not a usage error, not a signal), names `name` and says `why`; every
    /// file in `kept` has the bytes it had before.
    void ExpectRefused(const std::string& args, const std::string& name, const std::string& why,
                       const std::vector<std::string>& kept) {
        SCOPED_TRACE(args);
        std::vector<std::string> before;
        for (const auto& k : kept) before.push_back(testing::ReadBytes(k));
        const CliResult r = RunCli(args);
        EXPECT_EQ(r.exit_code, 1) << r.output;
        EXPECT_NE(r.output.find(name), std::string::npos) << r.output;
        EXPECT_NE(r.output.find(why), std::string::npos) << r.output;
        for (std::size_t i = 0; i < kept.size(); ++i) {
            EXPECT_TRUE(fs::exists(kept[i])) << kept[i];
            EXPECT_EQ(testing::ReadBytes(kept[i]), before[i]) << kept[i];
        }
    }

    fs::path dir_;
    std::string pairs_, rows_, xyz_;
};

TEST_F(CliOutputRule, ExistingOutputIsRefusedByEveryWriterWithoutForce) {
    const std::string old = (dir_ / "old.txt").string();
    Put(old, "precious\n");
    const std::string src = xyz_ + "/0000_src.xyz";
    const std::string tgt = xyz_ + "/0000_tgt.xyz";
    const std::string why = "already exists";
    // One row per writer of one file; each was replaced without --force before issue 44
    // (except run).
    for (const std::string& args : std::vector<std::string>{
             "generate --protocol partial --dataset procedural --pairs 1 --out " + old,
             "run --pairs " + pairs_ + " --methods identity -q --out " + old,
             "report " + rows_ + " --out " + old,
             "score --pairs " + pairs_ + " --transforms " + rows_ + " --method x --out " + old,
             "align " + src + " " + tgt + " --method identity --out " + old,
             "compare " + rows_ + " " + rows_ + " --json " + old,
             "import --xyz-dir " + xyz_ + " --out " + old,
             "merge " + rows_ + " --pairs " + pairs_ + " --methods identity --out " + old,
         }) {
        ExpectRefused(args, old, why, {old});
    }
    // --force replaces it (two writers suffice: the rule is one function).
    ASSERT_EQ(RunCli("report " + rows_ + " --out " + old + " --force").exit_code, 0);
    EXPECT_NE(testing::ReadBytes(old), "precious\n");
    Put(old, "precious\n");
    ASSERT_EQ(
        RunCli("align " + src + " " + tgt + " --method identity --force --out " + old).exit_code,
        0);
    EXPECT_NE(testing::ReadBytes(old), "precious\n");
}

TEST_F(CliOutputRule, OutputEqualToOrInsideAnInputIsRefusedEvenWithForce) {
    ExpectRefused("run --pairs " + pairs_ + " --methods identity -q --force --out " + pairs_,
                  pairs_, "same file as the input", {pairs_});
    ExpectRefused("report " + rows_ + " --force --out " + rows_, rows_, "same file as the input",
                  {rows_});
    // A new file inside the folder being imported or generated from (the next import or
    // generate would read it back as data).
    const std::string inside = xyz_ + "/new.h5";
    ExpectRefused("import --xyz-dir " + xyz_ + " --out " + inside, inside,
                  "inside the input " + xyz_, {});
    EXPECT_FALSE(fs::exists(inside));
    ExpectRefused(
        "generate --protocol partial --dataset " + xyz_ + " --split all --pairs 1 --out " + inside,
        inside, "inside the input", {});
    EXPECT_FALSE(fs::exists(inside));
}

TEST_F(CliOutputRule, SymbolicLinkOutputsAreRefused) {
    const fs::path elsewhere = dir_ / "elsewhere";
    fs::create_directories(elsewhere);
    const std::string link = (dir_ / "link").string();
    fs::create_directory_symlink(elsewhere, link);
    ExpectRefused("reproduce --tables table1 --quick --pairs 1 --out " + link, link,
                  "symbolic link", {});
    ExpectRefused("reproduce --tables table1 --quick --pairs 1 --out " + link + "/", link,
                  "symbolic link", {});
    EXPECT_TRUE(fs::is_empty(elsewhere));
    const std::string file_link = (dir_ / "file_link.txt").string();
    const std::string target = (dir_ / "target.txt").string();
    Put(target, "precious\n");
    fs::create_symlink(target, file_link);
    ExpectRefused("report " + rows_ + " --force --out " + file_link, file_link, "symbolic link",
                  {target});
    EXPECT_TRUE(fs::is_symlink(file_link));
}

TEST_F(CliOutputRule, PartAndLockFilesOfAnotherRunAreCoveredByItsLock) {
    // Another run writing OUT holds OUT.lock (flock, as OutputLock takes it) and streams rows
    // to OUT.part.
    const std::string out = (dir_ / "other.jsonl").string();
    const std::string part = out + ".part";
    Put(part, "{\"rows\": \"of the other run\"}\n");
    const int fd = ::open((out + ".lock").c_str(), O_RDWR | O_CREAT, 0644);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
    ExpectRefused("run --pairs " + pairs_ + " --methods identity -q --force --out " + part, part,
                  "another regbench process", {part});
    ExpectRefused("report " + rows_ + " --force --out " + part, part, "another regbench process",
                  {part});
    ExpectRefused("report " + rows_ + " --force --out " + out + ".lock", out + ".lock", "lock file",
                  {});
    ::close(fd);
}

TEST_F(CliOutputRule, ImportCheckpointNeverReplacesItsInputOrARunFolder) {
    const std::string pth = (dir_ / "m.pth").string();
    Put(pth, "not read: refused before");
    const CliResult probe =
        RunCli("import-checkpoint " + pth + " --from ogmm --out " + (dir_ / "probe").string());
    if (probe.output.find("no LibTorch") != std::string::npos) GTEST_SKIP() << probe.output;
    ExpectRefused("import-checkpoint " + pth + " --from ogmm --force --out " + pth, pth,
                  "same file as the input", {pth});
    // A training run folder: best/, last/ and the metrics stay.
    const fs::path run = dir_ / "run";
    fs::create_directories(run / "best");
    Put(run / "best" / "checkpoint.json", "{}");
    Put(run / "metrics.csv", "step\n");
    ExpectRefused("import-checkpoint " + pth + " --from ogmm --out " + run.string(), run.string(),
                  "already exists",
                  {(run / "best" / "checkpoint.json").string(), (run / "metrics.csv").string()});
    const std::string inner = (run / "m.pth").string();
    Put(inner, "weights");
    ExpectRefused("import-checkpoint " + inner + " --from ogmm --force --out " + run.string(),
                  run.string(), "holds the input", {inner, (run / "metrics.csv").string()});
    const std::string exported = (dir_ / "e.pth").string();
    Put(exported, "precious");
    ExpectRefused("export-checkpoint " + run.string() + " --to ogmm --out " + exported, exported,
                  "already exists", {exported});
}

}  // namespace
}  // namespace regbench
