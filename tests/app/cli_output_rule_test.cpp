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
#include "tests/app/expect_refused.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;
using testing::RunCli;
using testing::ExpectRefused;
using testing::Put;

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

}  // namespace
}  // namespace regbench
