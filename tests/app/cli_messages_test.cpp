// Issue 55, item 8 and issue 54, item 7: messages and exit codes of the CLI at its edges.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/testing/cli.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::RunCli;

// `inspect --json` on a pair file whose path is not UTF-8 ended in a raw nlohmann
// "type_error.316". Expected: exit 0 and valid JSON (the byte shown as U+FFFD), the same
// summary as the file under a UTF-8 name.
TEST(CliMessages, InspectJsonPrintsAPathThatIsNotUtf8) {
    const fs::path dir = testing::FreshTempDir("inspect_bytes");
    const std::string plain = testing::SmallPairFile((dir / "p.h5").string(), 2);
    const std::string odd = (dir / "p\xff.h5").string();
    fs::copy_file(plain, odd);
    const CliResult a = RunCli("inspect --json '" + plain + "'");
    const CliResult b = RunCli("inspect --json '" + odd + "'");
    ASSERT_EQ(a.exit_code, 0) << a.output;
    ASSERT_EQ(b.exit_code, 0) << b.output;
    const nlohmann::json ja = nlohmann::json::parse(a.output);
    const nlohmann::json jb = nlohmann::json::parse(b.output);
    EXPECT_EQ(jb.at("summary"), ja.at("summary"));
    EXPECT_EQ(jb.at("file").get<std::string>(), (dir / "p\xef\xbf\xbd.h5").string());
    fs::remove_all(dir);
}

/// A usage error: exit 2 and one line naming each of `words`.
void ExpectUsageError(const CliResult& r, const std::vector<std::string>& words) {
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find("usage error"), std::string::npos) << r.output;
    for (const auto& w : words) EXPECT_NE(r.output.find(w), std::string::npos) << w << r.output;
}

// Issue 54, item 7: `regbench frobnicate` answered "A subcommand is required", as if none had
// been given. Expected: the word named as an unknown subcommand, with the known ones.
TEST(CliMessages, UnknownSubcommandIsNamedWithTheKnownOnes) {
    const CliResult r = RunCli("frobnicate --out x");
    ExpectUsageError(r, {"unknown subcommand 'frobnicate'", "report", "reproduce",
                         "import-checkpoint"});
    EXPECT_EQ(r.output.find("A subcommand is required"), std::string::npos) << r.output;
    // None at all still says that one is required.
    ExpectUsageError(RunCli(""), {"A subcommand is required"});
}

// Issue 54, item 7: an unknown `reproduce --tables` name and an unknown `generate --split`
// exited 1, as if the data were at fault. Expected: usage errors (exit 2) naming the value,
// before anything is written.
TEST(CliMessages, UnknownTableAndSplitAreUsageErrors) {
    const fs::path dir = testing::FreshTempDir("usage_names");
    ExpectUsageError(RunCli("reproduce --quick --tables table9 --out " + (dir / "r").string()),
                     {"--tables", "'table9'", "table1_modelnet_partial"});
    EXPECT_FALSE(fs::exists(dir / "r"));
    ExpectUsageError(RunCli("generate --dataset procedural --split tset --pairs 1 --out " +
                            (dir / "p.h5").string()),
                     {"--split", "'tset'", "same_category/{train,val,test}"});
    EXPECT_FALSE(fs::exists(dir / "p.h5"));
    fs::remove_all(dir);
}

// Issue 54, item 7: `report --paper` took only full table ids and exited 1 on an unknown
// table or group. Expected: a table id or a prefix of one table, as `reproduce --tables`
// takes them; everything else a usage error naming the tables or the table's groups.
TEST(CliMessages, ReportPaperTakesTablePrefixesAndRefusesTheRestAsUsage) {
    const fs::path dir = testing::FreshTempDir("report_paper");
    const std::string pairs = testing::SmallPairFile((dir / "p.h5").string(), 2);
    const std::string rows = (dir / "r.jsonl").string();
    testing::RunCliOk("run --pairs " + pairs + " --methods identity -q --out " + rows);
    const CliResult ok = RunCli("report " + rows + " --format csv --paper table1:same_category");
    EXPECT_EQ(ok.exit_code, 0) << ok.output;
    EXPECT_NE(ok.output.find("paper:table1_modelnet_partial:same_category,identity,"),
              std::string::npos)
        << ok.output;
    const std::string report = "report " + rows + " --paper ";
    ExpectUsageError(RunCli(report + "table1:same"),
                     {"'same'", "table1_modelnet_partial", "same_category, cross_category"});
    ExpectUsageError(RunCli(report + "table1"), {"needs a column group", "same_category"});
    ExpectUsageError(RunCli(report + "table9"), {"'table9' names no paper table", "table3_indoor"});
    ExpectUsageError(RunCli(report + "supp"), {"several paper tables", "supp_complete"});
    ExpectUsageError(RunCli(report + "table4:x"), {"has no column groups"});
    fs::remove_all(dir);
}

// Issue 54, item 7: `report` on a pair file said "line 1: not JSON". Expected: the file named
// as a pair file, with the commands that read one (exit 1: the input, not the flags, is wrong).
TEST(CliMessages, ReportOnAPairFileNamesItAsOne) {
    const fs::path dir = testing::FreshTempDir("report_pairs");
    const std::string pairs = testing::SmallPairFile((dir / "p.h5").string(), 1);
    const CliResult r = RunCli("report " + pairs);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(pairs + ": a pair file (HDF5)"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("regbench inspect " + pairs), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("regbench run --pairs " + pairs), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("not JSON:"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench
