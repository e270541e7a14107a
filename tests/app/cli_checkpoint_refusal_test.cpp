// Issue 44 group 4: a checkpoint that cannot run (another format_version, a weights path leaving
// the folder or naming a device, a missing, empty, truncated or garbage weights file) ran, failed
// every row and exited 0. Expected: refused before the run, when the method is created (as a
// wrong --params is), naming the file and the problem, with no rows written. The checkpoint is a
// copy of the shipped data/models/deepgmr, damaged one way per case.
// Also the checkpoint writers under the output rule (import-checkpoint never replaces its input
// or a training run folder). Built only with LibTorch (tests/CMakeLists.txt).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/testing/cli.hpp"
#include "tests/testing/files.hpp"
#include "tests/app/expect_refused.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::RunCli;
using testing::ExpectRefused;
using testing::Put;

TEST(CliCheckpointRefusal, DamagedCheckpointsAreRefusedBeforeTheRun) {
    const char* src = std::getenv("REGBENCH_SOURCE_DIR");
    ASSERT_NE(src, nullptr);
    const fs::path dir = testing::FreshTempDir("checkpoint_refusal");
    const fs::path ck = dir / "ck";
    fs::copy(fs::path(src) / "data" / "models" / "deepgmr", ck);
    const fs::path json = ck / "checkpoint.json";
    const fs::path weights = ck / "weights.pt";
    const std::string good_json = testing::ReadBytes(json);
    const std::string good_weights = testing::ReadBytes(weights);
    ASSERT_GT(good_weights.size(), 100u);
    const std::string pairs = testing::SmallPairFile((dir / "p.h5").string(), 1);
    const std::string out = (dir / "r.jsonl").string();
    const std::string run = "run --pairs " + pairs + " --methods deepgmr-noicp -q --params " +
                            "'{\"deepgmr-noicp\": {\"checkpoint\": \"" + ck.string() +
                            "\"}}' --out " + out;
    const CliResult intact = RunCli(run);
    ASSERT_EQ(intact.exit_code, 0) << intact.output;  // the copy itself runs
    fs::remove(out);
    const auto with = [&](const char* key, nlohmann::json v) {
        return [&, key, v] {
            nlohmann::json j = nlohmann::json::parse(good_json);
            j[key] = v;
            std::ofstream(json, std::ios::trunc) << j.dump();
        };
    };
    const auto weights_as = [&](std::string bytes) {
        return [&, bytes] { std::ofstream(weights, std::ios::binary | std::ios::trunc) << bytes; };
    };
    struct Case {
        const char* name;
        std::function<void()> damage;
        std::string names;  ///< the file the refusal must name
        const char* reason;
    };
    const std::vector<Case> cases = {
        {"format_version 99", with("format_version", 99), json.string(),
         "format_version 99 is not supported"},
        {"weights ..", with("weights", "../weights.pt"), json.string(), "leaves the checkpoint"},
        {"weights absolute", with("weights", "/dev/zero"), json.string(), "absolute path"},
        {"weights missing", [&] { fs::remove(weights); }, weights.string(), "is missing"},
        {"weights empty", weights_as(""), weights.string(), "is empty"},
        {"weights truncated", weights_as(good_weights.substr(0, good_weights.size() / 2)),
         weights.string(), "truncated"},
        {"weights garbage", weights_as(std::string(good_weights.size(), 'x')), weights.string(),
         "not a torch weights archive"},
        {"weights a device",
         [&] {
             fs::remove(weights);
             fs::create_symlink("/dev/zero", weights);
         },
         weights.string(), "not a regular file"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        c.damage();
        const CliResult r = RunCli(run);
        EXPECT_GT(r.exit_code, 0) << r.output;
        EXPECT_LT(r.exit_code, 128) << r.output;
        EXPECT_NE(r.output.find(c.names), std::string::npos) << r.output;
        EXPECT_NE(r.output.find(c.reason), std::string::npos) << r.output;
        EXPECT_FALSE(fs::exists(out));
        EXPECT_FALSE(fs::exists(out + ".part"));
        std::ofstream(json, std::ios::trunc) << good_json;
        fs::remove(weights);
        std::ofstream(weights, std::ios::binary) << good_weights;
    }
    fs::remove_all(dir);
}

TEST(CliCheckpointRefusal, ImportCheckpointNeverReplacesItsInputOrARunFolder) {
    const fs::path dir_ = testing::FreshTempDir("import_output_rule");
    const std::string pth = (dir_ / "m.pth").string();
    Put(pth, "not read: refused before");
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
    fs::remove_all(dir_);
}

}  // namespace
}  // namespace regbench
