// Issue 44 group 6: every invalid number on a flag is a usage error (exit 2, one line naming the
// flag) before any work, and no output is left; the values come from the issue's list (an
// empty value as an unset shell variable gives, nan, inf, -1, 0, 1e400, 2^63, 10^9 threads).
// A transform translating beyond the coordinate limit is refused by `score` naming file:line.
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

TEST(CliFlagNumbers, InvalidNumbersAreUsageErrorsBeforeAnyWork) {
    const fs::path dir = testing::FreshTempDir("flag_numbers");
    const std::string pairs = testing::SmallPairFile((dir / "p.h5").string(), 2);
    const std::string rows = (dir / "r.jsonl").string();
    testing::RunCliOk("run --pairs " + pairs + " --methods identity -q --out " + rows);
    const std::string out = (dir / "out").string();
    const std::string gen = "generate --protocol partial --dataset procedural --out " + out + " ";
    const std::string deep = std::string(1000, '[') + std::string(1000, ']');
    struct Case {
        std::string args;
        const char* flag;  ///< the refusal names it
    };
    const std::vector<Case> cases = {
        {gen + "--pairs 0", "--pairs"},
        {gen + "--pairs 9223372036854775808", "--pairs"},
        {gen + "--pairs 2 --keep nan", "--keep"},
        {gen + "--pairs 2 --keep inf", "--keep"},
        {gen + "--pairs 2 --keep -1", "--keep"},
        {gen + "--pairs 2 --keep 0", "--keep"},
        {gen + "--pairs 2 --keep 1e400", "--keep"},
        {gen + "--pairs 2 --keep 1.5", "keep"},
        {gen + "--pairs 2 --max-rotation-deg ''", "--max-rotation-deg"},
        {gen + "--pairs 2 --max-translation ''", "--max-translation"},
        {gen + "--pairs 2 --noise-sigma -1", "--noise-sigma"},
        {gen + "--pairs 2 --eta 0", "--eta"},
        {gen + "--pairs 2 --points 0", "points"},
        {"generate --protocol overlap-sweep --dataset procedural --pairs 2 --sweep-keeps 0.5,nan "
         "--out " +
             out,
         "--sweep-keeps"},
        {"report " + rows + " --recall-r nan", "--recall-r"},
        {"report " + rows + " --recall-t inf", "--recall-t"},
        {"report " + rows + " --success-rre -1", "--success-rre"},
        {"report " + rows + " --success-rte 0", "--success-rte"},
        {"report " + rows + " --bootstrap 0", "--bootstrap"},
        {"compare " + rows + " " + rows + " --tolerance inf", "--tolerance"},
        {"compare " + rows + " " + rows + " --tolerance mae_r=inf", "--tolerance"},
        {"run --pairs " + pairs + " --methods identity -q --threads 1000000000 --out " + out,
         "--threads"},
        {"run --pairs " + pairs + " --methods identity -q --params '{\"identity\": " + deep +
             "}' --out " + out,
         "--params"},
        {"align " + pairs + " " + pairs + " --method identity --threads 1000000000", "--threads"},
        // Issue 55, items 7 and 8: accepted (1e18, inf, 1e400), exit 1 or exit 3 before.
        {"score --pairs " + pairs + " --transforms " + rows + " --method m --out " + out +
             " --rigid-tol 1e18",
         "--rigid-tol"},
        {"score --pairs " + pairs + " --transforms " + rows + " --method m --out " + out +
             " --rigid-tol 0.2",
         "--rigid-tol"},
        {"import --xyz-dir " + dir.string() + " --out " + out + " --eta inf", "--eta"},
        {"import --xyz-dir " + dir.string() + " --out " + out + " --eta 1e400", "--eta"},
        {"import --xyz-dir " + dir.string() + " --out " + out + " --eta nan", "--eta"},
        {"import --xyz-dir " + dir.string() + " --out " + out + " --eta -inf", "--eta"},
        {"import --xyz-dir " + dir.string() + " --out " + out + " --eta ''", "--eta"},
        {"import --xyz-dir " + dir.string() + " --out " + out + " --eta -1", "--eta"},
        {"import --xyz-dir " + dir.string() + " --out " + out + " --eta 0", "--eta"},
        {"compare " + rows + " " + rows + " --tolerance ''", "--tolerance"},
        {"generate --protocol jitter --dataset procedural --pairs 2 --noise-sigma 1e18 "
         "--noise-clip 1e18 --out " + out,
         "noise_clip"},
        {"train --model deepgmr-orig-xyz --max-steps 1 --lr 1e18 --out " + out, "--lr"},
        {"train --model deepgmr-orig-xyz --max-steps 1 --lr 2 --out " + out, "--lr"},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.args);
        const CliResult r = RunCli(c.args);
        EXPECT_EQ(r.exit_code, 2) << r.output;
        EXPECT_NE(r.output.find(c.flag), std::string::npos) << r.output;
        EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << "not one line: " << r.output;
        EXPECT_FALSE(fs::exists(out));
    }
    fs::remove_all(dir);
}

TEST(CliFlagNumbers, ScoreRefusesTranslationsBeyondTheCoordinateLimit) {
    const fs::path dir = testing::FreshTempDir("flag_numbers_score");
    const std::string pairs = testing::SmallPairFile((dir / "p.h5").string(), 1);
    const std::string t = (dir / "t.jsonl").string();
    std::ofstream(t) << R"({"pair": 0, "transform": [[1, 0, 0, 1e300], [0, 1, 0, 0], )"
                     << R"([0, 0, 1, 0], [0, 0, 0, 1]]})"
                     << "\n";
    const std::string out = (dir / "s.jsonl").string();
    const CliResult r =
        RunCli("score --pairs " + pairs + " --transforms " + t + " --method x --out " + out);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(t + ":1"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("coordinate limit"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
    fs::remove_all(dir);
}

TEST(CliFlagNumbers, ScoreTakesLogAndNpyAndRefusesAnotherExtensionAsUsage) {
    // Issue 54 item 6: the format is chosen by the extension; any other is a usage error
    // (exit 2, naming the file and the formats), a malformed .npy a data error (exit 1, naming
    // the file and the problem); neither writes anything.
    const fs::path dir = testing::FreshTempDir("flag_numbers_score_formats");
    const std::string pairs = testing::SmallPairFile((dir / "p.h5").string(), 1);
    const std::string out = (dir / "s.jsonl").string();
    const std::string txt = (dir / "t.txt").string();
    std::ofstream(txt) << "0 1 2\n";
    CliResult r =
        RunCli("score --pairs " + pairs + " --transforms " + txt + " --method x --out " + out);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("'" + txt + "': a transforms file must end in .jsonl (or .json), "
                            ".csv, .log (3DMatch) or .npy (NumPy)"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(out));
    const std::string npy = (dir / "t.npy").string();
    std::ofstream(npy) << "PK not numpy";
    r = RunCli("score --pairs " + pairs + " --transforms " + npy +
               " --method x --allow-unhashed --out " + out);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(npy + ": not a NumPy .npy file"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
    // A one-pair 3DMatch .log (the identity) scores one row.
    const std::string log = (dir / "t.log").string();
    std::ofstream(log) << "0 1 2\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
    r = RunCli("score --pairs " + pairs + " --transforms " + log +
               " --method x --allow-unhashed --out " + out);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("wrote 1 rows (0 missing)"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench
