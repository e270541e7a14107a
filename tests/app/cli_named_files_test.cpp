// Issue 44 group 5: every refusal names the file. Point clouds align cannot use (1 point, all
// points identical), hostile PLY/PCD/XYZ headers and bodies, and experiment files that cannot
// run (0 pairs, a table id leaving the report folder, an unknown method) are refused with the
// file's name and the reason, before any method runs, and nothing is written.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/testing/cli.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::RunCli;

struct FileCase {
    const char* name;    ///< file name (its extension picks the reader)
    const char* text;    ///< its content
    const char* reason;  ///< what the refusal must say besides the name
};

void ExpectNamedRefusal(const CliResult& r, const std::string& path, const std::string& reason) {
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(path), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(reason), std::string::npos) << r.output;
}

TEST(CliNamedFiles, AlignRefusesCloudsWithoutATransformBeforeAnyMethod) {
    const fs::path dir = testing::FreshTempDir("named_align");
    const std::string good = (dir / "good.xyz").string();
    std::ofstream(good) << "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
    const std::string out = (dir / "T.txt").string();
    for (const FileCase& c : std::vector<FileCase>{
             {"one.xyz", "0.5 0.5 0.5\n", "1 point(s); align needs at least 3"},
             {"same.xyz", "1 2 3\n1 2 3\n1 2 3\n1 2 3\n", "all 4 points are identical"},
         }) {
        SCOPED_TRACE(c.name);
        const std::string path = (dir / c.name).string();
        std::ofstream(path) << c.text;
        for (const std::string& args : {path + " " + good + " --method icp --out " + out,
                                        good + " " + path + " --method icp --out " + out}) {
            ExpectNamedRefusal(RunCli("align " + args), path, c.reason);
            EXPECT_FALSE(fs::exists(out));
        }
    }
    fs::remove_all(dir);
}

TEST(CliNamedFiles, HostilePointFilesAreRefusedByName) {
    const fs::path dir = testing::FreshTempDir("named_points");
    const std::string good = (dir / "good.xyz").string();
    std::ofstream(good) << "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
    const std::vector<FileCase> cases = {
        {"dup.ply",
         "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float x\nend_header\n0 0 0\n1 0 0\n0 1 0\n",
         "PLY vertex property 'x' is declared twice"},
        {"dup.pcd",
         "VERSION .7\nFIELDS x y x\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\n"
         "POINTS 3\nDATA ascii\n0 0 0\n1 0 0\n0 1 0\n",
         "PCD field 'x' is declared twice"},
        {"width.pcd",
         "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 5\nHEIGHT 1\n"
         "POINTS 3\nDATA ascii\n0 0 0\n1 0 0\n0 1 0\n",
         "does not match POINTS 3"},
        {"garbage.ply",
         "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nend_header\nthis is not\n1 0 0\n0 1 0\n",
         "holds 'this', not a number"},
        {"garbage.pcd",
         "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\n"
         "POINTS 3\nDATA ascii\n0 0 0\n1 0 0\n0 1 zz\n",
         "holds 'zz', not a number"},
        {"garbage.xyz", "0 0 0\n1 0 0\nabc\n", "garbage.xyz:3"},
    };
    for (const FileCase& c : cases) {
        SCOPED_TRACE(c.name);
        const std::string path = (dir / c.name).string();
        std::ofstream(path, std::ios::binary) << c.text;
        ExpectNamedRefusal(RunCli("align " + path + " " + good + " --method icp"), path, c.reason);
    }
    fs::remove_all(dir);
}

TEST(CliNamedFiles, ExperimentFilesThatCannotRunAreRefusedByName) {
    const fs::path dir = testing::FreshTempDir("named_experiments");
    const std::string experiment = R"({"id": "e1", "protocol": "partial", "split": "test",
                                       "dataset": "procedural")";
    const std::vector<FileCase> cases = {
        {"zero_pairs.json", "", "experiment 'e1' gets 0 pairs at this --pairs"},
        {"table_dots.json", "", "'table' must be a file stem"},
        {"unknown_method.json", "", "no_such_method"},
    };
    const std::vector<std::string> texts = {
        R"({"table": "t0", "title": "T", "experiments": [)" + experiment +
            R"(, "pairs": {"scale": 0.5}}]})",
        R"({"table": "../../escape", "title": "T", "experiments": [)" + experiment + "}]}",
        R"({"table": "t2", "title": "T", "methods": ["icp", "no_such_method"], "experiments": [)" +
            experiment + "}]}",
    };
    for (std::size_t i = 0; i < cases.size(); ++i) {
        SCOPED_TRACE(cases[i].name);
        const std::string path = (dir / cases[i].name).string();
        std::ofstream(path) << texts[i];
        const std::string out = (dir / "out").string();
        ExpectNamedRefusal(RunCli("reproduce --experiment " + path + " --pairs 1 --out " + out),
                           path, cases[i].reason);
        EXPECT_FALSE(fs::exists(dir / "escape.md"));
        EXPECT_FALSE(fs::exists(fs::path(out) / "results"));
    }
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench
