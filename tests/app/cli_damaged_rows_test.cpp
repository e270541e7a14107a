// Issue 44 group 3: result rows no writer would have written are refused by every reader
// (report, compare, merge, run --resume) naming the file and line; compare never PASSes on them.
// Each case damages line 1 of a real `run` output; the expected refusal is the line's address.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
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

struct Damage {
    const char* name;
    std::function<void(nlohmann::json&)> apply;  ///< on line 1's row
    const char* prefix = "";                     ///< bytes put before line 1
};

std::vector<std::string> Lines(const std::string& path) {
    std::ifstream in(path);
    std::vector<std::string> lines;
    for (std::string l; std::getline(in, l);) lines.push_back(l);
    return lines;
}

TEST(CliDamagedRows, EveryReaderRefusesRowsNoWriterWrites) {
    const fs::path dir = testing::FreshTempDir("damaged_rows");
    const std::string pairs = testing::SmallPairFile((dir / "p.h5").string(), 2);
    const std::string good = (dir / "good.jsonl").string();
    testing::RunCliOk("run --pairs " + pairs + " --methods identity -q --out " + good);
    const std::vector<std::string> lines = Lines(good);
    ASSERT_EQ(lines.size(), 2u);
    const auto set = [](const char* key, nlohmann::json v) {
        return [key, v](nlohmann::json& row) { row["metrics"][key] = v; };
    };
    const std::vector<Damage> cases = {
        {"bom", [](nlohmann::json&) {}, "\xEF\xBB\xBF"},
        {"mae_r_negative", set("mae_r", -1.0)},
        {"mae_t_1e308", set("mae_t", 1e308)},
        {"rre_above_180", set("rre", 181.0)},
        {"ccd_null", set("ccd", nullptr)},
        {"pair_minus_1", [](nlohmann::json& r) { r["pair"] = -1; }},
        {"pair_1e20", [](nlohmann::json& r) { r["pair"] = 1e20; }},
        {"method_empty", [](nlohmann::json& r) { r["method"] = ""; }},
        {"gt_scaled",
         [](nlohmann::json& r) {
             r["gt_transform"] = {{2, 0, 0, 0}, {0, 2, 0, 0}, {0, 0, 2, 0}, {0, 0, 0, 1}};
         }},
        {"transform_1e300", [](nlohmann::json& r) { r["transform"][0][3] = 1e300; }},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.name);
        nlohmann::json row = nlohmann::json::parse(lines[0]);
        c.apply(row);
        const std::string bad = (dir / (std::string(c.name) + ".jsonl")).string();
        std::ofstream(bad) << c.prefix << row.dump() << "\n" << lines[1] << "\n";
        const std::string where = bad + ":1";
        for (const std::string& args : std::vector<std::string>{
                 "report " + bad,
                 "compare " + good + " " + bad,
                 "compare " + bad + " " + good,
                 "merge " + bad + " --pairs " + pairs + " --methods identity --out " +
                     (dir / "m.jsonl").string(),
             }) {
            SCOPED_TRACE(args);
            const CliResult r = RunCli(args);
            EXPECT_EQ(r.exit_code, 1) << r.output;
            EXPECT_NE(r.output.find(where), std::string::npos) << r.output;
            EXPECT_EQ(r.output.find("PASS"), std::string::npos) << r.output;
        }
        EXPECT_FALSE(fs::exists(dir / "m.jsonl"));
        // --resume: the damaged row is refused, never kept (the final file would differ from
        // an uninterrupted run's).
        const std::string out = (dir / "resumed.jsonl").string();
        fs::copy_file(bad, out + ".part", fs::copy_options::overwrite_existing);
        const CliResult r =
            RunCli("run --pairs " + pairs + " --methods identity -q --resume --out " + out);
        EXPECT_EQ(r.exit_code, 1) << r.output;
        EXPECT_NE(r.output.find(out + ".part:1"), std::string::npos) << r.output;
        EXPECT_FALSE(fs::exists(out));
        fs::remove(out + ".part");
    }
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench
