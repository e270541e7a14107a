// Issue 44 group 2: no input makes regbench wait for ever or read another file. A FIFO given as
// any input, a pair file linking to a FIFO, and an xyz folder linking to /dev/zero must each be
// refused by name within seconds. Every command runs under `timeout 60`, so a regression shows
// as exit 124 instead of a hung test.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/testing/cli.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/hostile_pair_files.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::RunCli;

CliResult RunBounded(const std::string& args) { return testing::RunCliWithin(60, args); }

TEST(CliNoHang, FifoInputsAreRefusedByName) {
    const fs::path dir = testing::FreshTempDir("no_hang");
    const std::string fifo = (dir / "in.fifo").string();
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    const std::string pairs = testing::SmallPairFile((dir / "p.h5").string(), 1);
    const std::string rows = (dir / "r.jsonl").string();
    testing::RunCliOk("run --pairs " + pairs + " --methods identity -q --out " + rows);
    const std::string xyz = (dir / "xyz").string();
    ASSERT_EQ(RunCli("export " + pairs + " --out " + xyz).exit_code, 0);
    const std::string src = xyz + "/0000_src.xyz";
    const std::string tgt = xyz + "/0000_tgt.xyz";
    const std::string o = (dir / "o").string();
    for (const std::string& args : std::vector<std::string>{
             "report " + fifo,
             "compare " + rows + " " + fifo,
             "merge " + fifo + " --pairs " + pairs + " --methods identity --out " + o + "1",
             "align " + src + " " + tgt + " --method identity --gt " + fifo,
             "align " + fifo + " " + tgt + " --method identity",
             "score --pairs " + pairs + " --transforms " + fifo + ".jsonl --method x --out " + o +
                 "2",
             "inspect " + fifo,
             "reproduce --experiment " + fifo + " --out " + o + "3",
             "report " + rows + " --paper-file " + fifo + " --paper table1_modelnet_partial",
         }) {
        SCOPED_TRACE(args);
        // score's transforms must end in .jsonl: a second FIFO with that name.
        if (args.find(fifo + ".jsonl") != std::string::npos && !fs::exists(fifo + ".jsonl")) {
            ASSERT_EQ(::mkfifo((fifo + ".jsonl").c_str(), 0600), 0);
        }
        const CliResult r = RunBounded(args);
        EXPECT_NE(r.exit_code, 124) << "hung: " << r.output;
        EXPECT_GT(r.exit_code, 0) << r.output;
        EXPECT_NE(r.output.find(fifo), std::string::npos) << r.output;
    }
    fs::remove_all(dir);
}

TEST(CliNoHang, PairFileLinkingToAFifoIsRefused) {
    const fs::path dir = testing::FreshTempDir("no_hang_link");
    const std::string fifo = (dir / "target.fifo").string();
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    const std::string h5 = (dir / "linked.h5").string();
    testing::WriteHostile(h5, {"fifo_link", "", [&fifo](hid_t f) {
                                   H5Ldelete(f, "/pairs/000001/source", H5P_DEFAULT);
                                   H5Lcreate_external(fifo.c_str(), "/x", f, "/pairs/000001/source",
                                                      H5P_DEFAULT, H5P_DEFAULT);
                               }});
    for (const std::string& args :
         {"inspect " + h5,
          "run --pairs " + h5 + " --methods identity -q --out " + (dir / "r.jsonl").string()}) {
        SCOPED_TRACE(args);
        const CliResult r = RunBounded(args);
        EXPECT_NE(r.exit_code, 124) << "hung: " << r.output;
        EXPECT_GT(r.exit_code, 0) << r.output;
        EXPECT_NE(r.output.find("external link"), std::string::npos) << r.output;
    }
    fs::remove_all(dir);
}

TEST(CliNoHang, ImportDoesNotFollowLinksToDevices) {
    const fs::path dir = testing::FreshTempDir("no_hang_import");
    const fs::path xyz = dir / "xyz";
    fs::create_directories(xyz);
    std::ofstream(xyz / "0000_tgt.xyz") << "0 0 0\n1 0 0\n0 1 0\n";
    std::ofstream(xyz / "0000_gt.txt") << "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
    fs::create_symlink("/dev/zero", xyz / "0000_src.xyz");
    const CliResult r =
        RunBounded("import --xyz-dir " + xyz.string() + " --out " + (dir / "o.h5").string());
    EXPECT_NE(r.exit_code, 124) << "hung: " << r.output;
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("0000_src.xyz: not a regular file"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "o.h5"));
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench
