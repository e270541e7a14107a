// One CLI contract (issue 26): usage errors exit 2 with one plain line before any work,
// refusals of input exit 1, `compare` exits 1 on FAIL and 3 when it cannot tell, and `run`
// never replaces an existing --out unless told to.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "reports/compare.hpp"
#include "runners/result_row.hpp"
#include "tests/testing/cli.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;

using testing::CliResult;
using testing::RunCli;

fs::path Dir() { return testing::TempFolder("cli_contract"); }

/// A tolerance as the docs write it (shortest form: 0.1, 0.001).
std::string Num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

/// `n` rows of method icp on pairs 0..n-1 as `run` writes them (every key of the typed row),
/// mae_r = 1 + k + shift (the compared metrics alike).
void WriteRows(const fs::path& path, int n, double shift, Status status) {
    std::vector<ResultRow> rows(static_cast<std::size_t>(n));
    for (std::size_t k = 0; k < rows.size(); ++k) {
        const double v = 1.0 + static_cast<double>(k) + shift;
        rows[k].pair = k;
        rows[k].method = "icp";
        rows[k].status = status;
        rows[k].data.pairs_file = "p.h5";
        rows[k].metrics.mae_r = rows[k].metrics.mae_t = rows[k].metrics.ccd = v;
        rows[k].metrics.rre = rows[k].metrics.rte = v;
    }
    WriteResultRows(path.string(), rows);
}

/// A usage error: exit 2 and exactly one line of output that names `what`.
void ExpectUsageError(const CliResult& r, const std::string& what) {
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find(what), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("1797693"), std::string::npos) << r.output;
}

// Issue 55, item 6: `regbench align` had no scale guard (Python's align got one; rienet on
// 200,000 points asked for 160 GB and printed a 34-frame backtrace). Expected: the guard of
// run and Python's align (runners/scale_guard RequireCallScale): an O(N*M) call on a cloud
// above --max-points (default 20,000) is refused before it runs, naming the method, both point
// counts and the limit, exit 1, nothing written; --max-points 0 lifts it; a method that is not
// O(N*M) (icp; cpd in its default mode) is not guarded.
TEST(CliContract, AlignHasTheScaleGuardOfRun) {
    const fs::path dir = testing::FreshTempDir("align_scale_guard");
    const std::string cloud = (dir / "cloud.xyz").string();
    std::string xyz;
    for (int k = 0; k < 200; ++k) {  // 200 distinct points in the unit cube
        xyz += std::to_string(k / 200.0) + " " + std::to_string((k * 7 % 200) / 200.0) + " " +
               std::to_string((k * 13 % 200) / 200.0) + "\n";
    }
    testing::WriteBytes(cloud, xyz);
    const std::string out = (dir / "T.txt").string();
    const std::string dense = "align " + cloud + " " + cloud +
                              " --method cpd --params '{\"e_step\": \"dense\"}' --out " + out;
    const CliResult refused = RunCli(dense + " --max-points 100");
    EXPECT_EQ(refused.exit_code, 1) << refused.output;
    EXPECT_NE(refused.output.find("align: cpd is O(N*M): source has 200 points, target 200, "
                                  "above max_points 100"),
              std::string::npos)
        << refused.output;
    EXPECT_NE(refused.output.find("pass --max-points 0"), std::string::npos) << refused.output;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_EQ(RunCli(dense + " --max-points 0").exit_code, 0);
    EXPECT_TRUE(fs::exists(out));
    EXPECT_EQ(RunCli(dense + " --max-points 200 --force").exit_code, 0);  // not above it
    for (const char* method : {"icp", "cpd"}) {
        const CliResult r =
            RunCli("align " + cloud + " " + cloud + " --method " + method + " --max-points 100");
        EXPECT_EQ(r.exit_code, 0) << method << ": " << r.output;
    }
    fs::remove_all(dir);
}

TEST(CliContract, CompareFailsWhenEveryCandidateCallFailed) {
    const fs::path base = Dir() / "base2.jsonl", bad = Dir() / "bad2.jsonl";
    WriteRows(base, 2, 0.0, Status::kOk);
    WriteRows(bad, 2, 0.0, Status::kFailed);  // same metrics: only the status tells
    const CliResult r = RunCli("compare " + base.string() + " " + bad.string());
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("Verdict: FAIL"), std::string::npos) << r.output;
    EXPECT_EQ(
        RunCli("compare " + base.string() + " " + bad.string() + " --allow-new-failures").exit_code,
        3);  // 2 pairs cannot reach p < 0.05 (2 / 2^2 = 0.5): inconclusive, never PASS
}

TEST(CliContract, CompareOnFivePairsIsInconclusive) {
    const fs::path base = Dir() / "base5.jsonl", worse = Dir() / "worse5.jsonl";
    WriteRows(base, 5, 0.0, Status::kOk);
    WriteRows(worse, 5, 5.0, Status::kOk);
    const CliResult r = RunCli("compare " + base.string() + " " + worse.string());
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find("Verdict: INCONCLUSIVE"), std::string::npos) << r.output;
    // 50 identical pairs: every difference is zero, nothing changed: PASS.
    WriteRows(base, 50, 0.0, Status::kOk);
    EXPECT_EQ(RunCli("compare " + base.string() + " " + base.string()).exit_code, 0);
}

TEST(CliContract, UsageErrorsExitTwoWithOneLine) {
    const fs::path base = Dir() / "base_usage.jsonl";
    WriteRows(base, 6, 0.0, Status::kOk);
    ExpectUsageError(
        RunCli("compare " + base.string() + " " + base.string() + " --tolerance mae_x=1"), "mae_x");
    ExpectUsageError(RunCli("compare " + base.string() + " " + base.string() + " --alpha 2"),
                     "--alpha");
    ExpectUsageError(RunCli("run --pairs x.h5 --methods identity --out y.jsonl --jobs 0"),
                     "--jobs");
    ExpectUsageError(RunCli("run --pairs x.h5 --methods identity --out y.jsonl --shard 2/2"),
                     "--shard");
    ExpectUsageError(RunCli("compare " + base.string() + " " + base.string() + " --no-such-flag"),
                     "--no-such-flag");
    // reproduce refuses --jobs 0 before it generates any pair file.
    const fs::path out = Dir() / "reproduce_jobs0";
    fs::remove_all(out);
    ExpectUsageError(RunCli("reproduce --quick --jobs 0 --out " + out.string()), "--jobs");
    EXPECT_FALSE(fs::exists(out));
    // An unknown dataset is a refusal of input naming every built-in name (issue 26: the
    // message left out indoor-sim).
    const CliResult dataset = RunCli(
        "generate --protocol partial --dataset nosuch --split test --pairs 1 --seed 1 "
        "--out " +
        (Dir() / "nosuch.h5").string());
    EXPECT_EQ(dataset.exit_code, 1) << dataset.output;
    EXPECT_NE(dataset.output.find("cgal, procedural; indoor-sim"), std::string::npos)
        << dataset.output;
    // A refusal of input (a missing file) is exit 1.
    EXPECT_EQ(
        RunCli("compare " + (Dir() / "missing.jsonl").string() + " " + base.string()).exit_code, 1);
}

// Issue 41 item 5: unknown method and protocol names exited 1 (an input refusal) and `run
// --method icp` said only that --methods is required; they are usage errors (exit 2, one line
// before any work) naming the known names with the nearest one as a "did you mean".
TEST(CliContract, UnknownNamesAreUsageErrorsWithADidYouMean) {
    const fs::path out = Dir() / "names.jsonl";
    fs::remove(out);
    const std::string run =
        "run --pairs " + (Dir() / "none.h5").string() + " --out " + out.string();
    ExpectUsageError(RunCli(run + " --methods icpp"), "unknown method 'icpp' (did you mean 'icp'?");
    ExpectUsageError(RunCli(run + " --methods icp,fgrr"), "did you mean 'fgr'?");
    ExpectUsageError(RunCli(run + " --methods icp --params '{\"icp\": {\"max_iteration\": 3}}'"),
                     "max_iteration");
    ExpectUsageError(RunCli(run + " --method icp"), "usage error: run takes --methods NAME");
    EXPECT_FALSE(fs::exists(out));
    ExpectUsageError(RunCli("align a.ply b.ply --method cdp"), "did you mean 'cpd'?");
    const std::string generate =
        "generate --dataset procedural --split test --pairs 1 --seed 1 "
        "--out " +
        (Dir() / "names.h5").string();
    ExpectUsageError(RunCli(generate + " --protocol parital"),
                     "unknown protocol 'parital' (did you mean 'partial'?");
    ExpectUsageError(RunCli(generate + " --pairing share"), "did you mean 'shared'?");
    EXPECT_FALSE(fs::exists(Dir() / "names.h5"));
}

// Issue 41 item 5: `generate --pairs N` above the split's items silently reused items.
TEST(CliContract, GenerateSaysWhenPairsReuseItems) {
    const fs::path out = Dir() / "reuse.h5";
    fs::remove(out);
    const std::string dir = Dir().string();
    // Two stored pairs exported as files: a folder dataset of 4 items (2 sources, 2 targets).
    const fs::path two = Dir() / "two.h5", files = Dir() / "two_xyz";
    fs::remove(two);
    fs::remove_all(files);
    testing::SmallPairFile(two.string(), 2);
    ASSERT_EQ(RunCli("export " + two.string() + " --out " + files.string()).exit_code, 0);
    const std::string generate = "generate --protocol partial --dataset " + files.string() +
                                 " --split all --points 32 --seed 1 --out " + out.string();
    const CliResult many = RunCli(generate + " --pairs 5");
    EXPECT_EQ(many.exit_code, 0) << many.output;
    EXPECT_NE(many.output.find("--pairs 5 is more than the 4 items"), std::string::npos)
        << many.output;
    EXPECT_NE(many.output.find("reuses items"), std::string::npos) << many.output;
    fs::remove(out);
    const CliResult few = RunCli(generate + " --pairs 4");
    EXPECT_EQ(few.exit_code, 0) << few.output;
    EXPECT_EQ(few.output.find("reuses items"), std::string::npos) << few.output;
}

// README command 1 failed in a fresh clone: `reproduce --out out/reproduce` stopped with
// "out/reproduce.lock: cannot create lock file" because `out/` did not exist. A command whose
// output is a folder creates the folder's missing parents (as `mkdir -p`); expected from that
// rule: exit 0 and the folders exist. A one-file output keeps refusing a missing directory.
TEST(CliContract, FolderOutputsCreateTheirMissingParents) {
    const fs::path dir = Dir() / "parents";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path pairs = dir / "pairs.h5";
    ASSERT_EQ(RunCli("generate --protocol partial --dataset procedural --split test --pairs 1 "
                     "--seed 1 --out " +
                     pairs.string())
                  .exit_code,
              0);
    const CliResult exported =
        RunCli("export " + pairs.string() + " --out " + (dir / "a/b/xyz").string());
    EXPECT_EQ(exported.exit_code, 0) << exported.output;
    EXPECT_TRUE(fs::is_directory(dir / "a/b/xyz")) << exported.output;
    const CliResult reproduced =
        RunCli("reproduce --tables table1 --pairs 1 --methods identity --timeout 0 --out " +
               (dir / "c/d/rep").string());
    EXPECT_EQ(reproduced.exit_code, 0) << reproduced.output;
    EXPECT_TRUE(fs::exists(dir / "c/d/rep/tables.md")) << reproduced.output;
    const CliResult one_file =
        RunCli("run --pairs " + pairs.string() + " --methods identity -q --out " +
               (dir / "e/f/run.jsonl").string());
    EXPECT_EQ(one_file.exit_code, 1) << one_file.output;
    EXPECT_NE(one_file.output.find("does not exist"), std::string::npos) << one_file.output;
    EXPECT_FALSE(fs::exists(dir / "e")) << one_file.output;
}

TEST(CliContract, RunRefusesAnExistingOutUnlessResumeOrForce) {
    const fs::path pairs = Dir() / "pairs.h5", out = Dir() / "run.jsonl";
    fs::remove(pairs);
    fs::remove(out);
    testing::SmallPairFile(pairs.string(), 2);
    const std::string run = "run --pairs " + pairs.string() + " -q --out " + out.string();
    ASSERT_EQ(RunCli(run + " --methods identity").exit_code, 0);
    const std::string first = testing::ReadBytes(out);
    const CliResult again = RunCli(run + " --methods icp");
    EXPECT_EQ(again.exit_code, 1) << again.output;
    EXPECT_NE(again.output.find(out.string() + ": already exists"), std::string::npos)
        << again.output;
    EXPECT_EQ(testing::ReadBytes(out), first);  // untouched
    EXPECT_EQ(RunCli(run + " --methods identity --resume").exit_code, 0);
    EXPECT_EQ(testing::ReadBytes(out), first);  // every row resumed
    ExpectUsageError(RunCli(run + " --methods identity --resume --force"), "--force");
    ASSERT_EQ(RunCli(run + " --methods icp --force").exit_code, 0);
    EXPECT_NE(testing::ReadBytes(out).find("\"method\":\"icp\""), std::string::npos);
}

TEST(CliContract, CompareDefaultTolerancesAgreeInCodeHelpAndDocs) {
    // The one source is DefaultTolerances(); --help and docs/reports.md must print its values.
    const auto d = DefaultTolerances();
    const std::string listed = "mae_r=" + Num(d.at("mae_r")) + ",mae_t=" + Num(d.at("mae_t")) +
                               ",ccd=" + Num(d.at("ccd")) + ",rre=" + Num(d.at("rre")) +
                               ",rte=" + Num(d.at("rte"));
    const CliResult help = RunCli("compare --help");
    EXPECT_EQ(help.exit_code, 0);
    EXPECT_NE(help.output.find(listed), std::string::npos) << listed << "\n" << help.output;
    EXPECT_NE(help.output.find("3 INCONCLUSIVE"), std::string::npos) << help.output;
    const char* src = std::getenv("REGBENCH_SOURCE_DIR");
    ASSERT_NE(src, nullptr);
    const std::string docs = testing::ReadBytes(fs::path(src) / "docs" / "reports.md");
    const std::string row = "| default tolerance | " + Num(d.at("mae_r")) + " | " +
                            Num(d.at("mae_t")) + " | " + Num(d.at("ccd")) + " | " +
                            Num(d.at("rre")) + " | " + Num(d.at("rte")) + " |";
    EXPECT_NE(docs.find(row), std::string::npos) << row;
    EXPECT_NE(docs.find("3 `INCONCLUSIVE`"), std::string::npos);
}

TEST(CliContract, ReportPaperInEveryFormatAndNoMixedSubsets) {
    const fs::path pairs = Dir() / "pairs4.h5", all = Dir() / "all4.jsonl",
                   shard = Dir() / "shard4.jsonl";
    for (const auto& p : {pairs, all, shard}) fs::remove(p);
    ASSERT_EQ(RunCli("generate --protocol partial --dataset procedural --split test --pairs 4 "
                     "--seed 1 --out " +
                     pairs.string())
                  .exit_code,
              0);
    ASSERT_EQ(RunCli("run --pairs " + pairs.string() + " --methods icp -q --out " + all.string())
                  .exit_code,
              0);
    ASSERT_EQ(RunCli("run --pairs " + pairs.string() + " --methods identity --shard 0/2 -q --out " +
                     shard.string())
                  .exit_code,
              0);
    const std::string paper = " --paper table1_modelnet_partial:same_category";
    // CSV carries the paper's cells (Tab. 1 same-category ICP MAE(R) 10.333, from
    // data/paper/ogmm_wacv2023_tables.json) and our pair count.
    const CliResult csv = RunCli("report " + all.string() + " --format csv" + paper);
    EXPECT_EQ(csv.exit_code, 0) << csv.output;
    // One record per cell, as every table's CSV (reports/table.hpp).
    const std::string table = "paper:table1_modelnet_partial:same_category,icp,";
    EXPECT_NE(csv.output.find(table + "pairs,pairs,measured,4,"), std::string::npos) << csv.output;
    EXPECT_NE(csv.output.find(table + "paper:mae_r,paper mae_r,paper,10.333,"), std::string::npos)
        << csv.output;
    for (const char* format : {"json", "latex", "md"}) {
        const CliResult r = RunCli("report " + all.string() + " --format " + format + paper);
        EXPECT_EQ(r.exit_code, 0) << r.output;
        EXPECT_NE(r.output.find("10.333"), std::string::npos) << format << ": " << r.output;
    }
    // icp on 4 pairs and identity on 2 (shard 0/2) of one file: refused, or compared on the 2.
    const CliResult mixed = RunCli("report " + all.string() + " " + shard.string() + paper);
    EXPECT_EQ(mixed.exit_code, 1) << mixed.output;
    EXPECT_NE(mixed.output.find("icp: 4"), std::string::npos) << mixed.output;
    EXPECT_NE(mixed.output.find("identity: 2"), std::string::npos) << mixed.output;
    const CliResult common =
        RunCli("report " + all.string() + " " + shard.string() + paper + " --common-pairs");
    EXPECT_EQ(common.exit_code, 0) << common.output;
    EXPECT_NE(common.output.find("restricted to the 2 pairs every method has"), std::string::npos)
        << common.output;
    EXPECT_NE(common.output.find("| icp | 2 |"), std::string::npos) << common.output;
}

}  // namespace
}  // namespace regbench
