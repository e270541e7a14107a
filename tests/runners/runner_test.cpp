#include "runners/runner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "protocols/pair_file.hpp"
#include "runners/registry.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/synthetic_pair_file.hpp"
#include "tests/testing/temp_dir_test.hpp"

namespace regbench {
namespace {

class RunnerTest : public testing::PairFileTest {
protected:
    RunnerTest() : PairFileTest(6, 50, 10, 3) {}

    RunOptions Options(const std::string& out) const {
        RunOptions o;
        o.pairs_path = pairs_;
        o.methods = ParseMethodSpecs("identity", {});
        o.out_path = Path(out);
        o.progress = false;
        return o;
    }
    /// Runs `a` and `b` and expects their rows to agree on `keys`, row by row in file order;
    /// returns b's rows.
    std::vector<nlohmann::json> ExpectSameRows(const RunOptions& a, const RunOptions& b,
                                               const std::vector<std::string>& keys) {
        RunBenchmark(a);
        RunBenchmark(b);
        const auto ra = ReadJsonl(a.out_path);
        const auto rb = ReadJsonl(b.out_path);
        EXPECT_EQ(ra.size(), rb.size());
        for (std::size_t i = 0; i < std::min(ra.size(), rb.size()); ++i) {
            for (const auto& key : keys)
                EXPECT_EQ(ra[i][key], rb[i][key]) << "row " << i << " " << key;
        }
        return rb;
    }
};

TEST_F(RunnerTest, WritesOneRowPerPairAndMethodWithRequiredKeys) {
    const RunOptions o = Options("r.jsonl");
    const RunSummary s = RunBenchmark(o);
    EXPECT_EQ(s.rows_written, 6u);
    EXPECT_FALSE(std::filesystem::exists(o.out_path + ".part"));
    const auto rows = ReadJsonl(o.out_path);
    ASSERT_EQ(rows.size(), 6u);
    for (std::size_t k = 0; k < rows.size(); ++k) {
        for (const char* key : {"pair", "method", "params", "transform", "seconds", "iterations",
                                "status", "message", "metrics", "data"}) {
            EXPECT_TRUE(rows[k].contains(key)) << key;
        }
        EXPECT_EQ(rows[k]["pair"], k);
        EXPECT_EQ(rows[k]["method"], "identity");
        EXPECT_EQ(rows[k]["status"], "ok");
        EXPECT_EQ(rows[k]["transform"].size(), 4u);
        EXPECT_EQ(rows[k]["data"]["dataset"], "synthetic");
    }
    // Identity against a 5k-degree rotation about z: rre = 5k exactly.
    EXPECT_NEAR(rows[3]["metrics"]["rre"].get<double>(), 15.0, 1e-6);
}

TEST_F(RunnerTest, RowsRecordConventionOverlapAndGroundTruth) {
    RunOptions o = Options("typed.jsonl");
    o.euler = EulerConvention::kXyz;
    RunBenchmark(o);
    const auto raw = ReadJsonl(o.out_path);
    const auto rows = ReadResultRows(o.out_path);
    ASSERT_EQ(rows.size(), 6u);
    const PairSet set = ReadPairFile(pairs_);
    for (std::size_t k = 0; k < rows.size(); ++k) {
        EXPECT_EQ(raw[k]["euler"], "xyz");
        EXPECT_EQ(rows[k].euler, EulerConvention::kXyz);
        EXPECT_EQ(rows[k].status, Status::kOk);
        EXPECT_EQ(rows[k].source_overlap_ratio, set.pairs[k].source_overlap_ratio);
        EXPECT_EQ(rows[k].target_overlap_ratio, set.pairs[k].target_overlap_ratio);
        // The points the call had (Tab. 6's points column reads them).
        EXPECT_EQ(raw[k]["source_points"], set.pairs[k].source.rows());
        EXPECT_EQ(rows[k].source_points, static_cast<std::size_t>(set.pairs[k].source.rows()));
        EXPECT_EQ(rows[k].target_points, static_cast<std::size_t>(set.pairs[k].target.rows()));
        ASSERT_TRUE(rows[k].gt_transform.has_value());
        EXPECT_EQ(*rows[k].gt_transform, set.pairs[k].T_gt);
        EXPECT_EQ(rows[k].origin, o.out_path + ":" + std::to_string(k + 1));
        // Writing the typed row back gives the same line (no key lost or renamed).
        EXPECT_EQ(nlohmann::json(rows[k]), raw[k]);
    }
}

TEST_F(RunnerTest, ParallelJobsGiveTheSameRowsInTheSameOrder) {
    RunOptions a = Options("a.jsonl");
    RunOptions b = Options("b.jsonl");
    b.jobs = 3;
    ExpectSameRows(a, b, {"pair", "transform", "metrics"});
}

TEST_F(RunnerTest, ResumeSkipsFinishedRowsAndDropsATornLine) {
    RunOptions o = Options("resume.jsonl");
    RunBenchmark(o);
    auto rows = ReadJsonl(o.out_path);
    // Simulate an interrupted run: two complete rows and half a third one.
    {
        std::ofstream part(o.out_path + ".part");
        part << rows[0].dump() << "\n" << rows[1].dump() << "\n" << rows[2].dump().substr(0, 20);
    }
    std::filesystem::remove(o.out_path);
    o.resume = true;
    const RunSummary s = RunBenchmark(o);
    EXPECT_EQ(s.rows_skipped, 2u);
    EXPECT_EQ(s.rows_written, 4u);
    EXPECT_EQ(ReadJsonl(o.out_path).size(), 6u);
}

TEST_F(RunnerTest, ResumeRefusesRowsOfAnotherEulerConvention) {
    RunOptions o = Options("euler.jsonl");
    RunBenchmark(o);  // zyx
    o.resume = true;
    o.euler = EulerConvention::kXyz;
    try {
        RunBenchmark(o);
        FAIL() << "resumed zyx rows into an xyz run";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("--euler zyx"), std::string::npos) << e.what();
    }
}

TEST_F(RunnerTest, ShardsPartitionThePairs) {
    std::size_t total = 0;
    for (int i = 0; i < 3; ++i) {
        RunOptions o = Options("shard" + std::to_string(i) + ".jsonl");
        o.shard_index = i;
        o.shard_count = 3;
        RunBenchmark(o);
        for (const auto& r : ReadJsonl(o.out_path)) {
            EXPECT_EQ(r["pair"].get<int>() % 3, i);
            ++total;
        }
    }
    EXPECT_EQ(total, 6u);
}

TEST_F(RunnerTest, IsolatedCallsGiveTheSameResult) {
    RunOptions a = Options("inproc.jsonl");
    RunOptions b = Options("isolated.jsonl");
    b.timeout_seconds = 30.0;
    for (const auto& row : ExpectSameRows(a, b, {"transform"})) EXPECT_EQ(row["status"], "ok");
}

TEST_F(RunnerTest, BadInputFailsBeforeWritingAnything) {
    RunOptions o = Options("never.jsonl");
    o.pairs_path = (dir_ / "missing.h5").string();
    try {
        RunBenchmark(o);
        FAIL() << "missing pair file accepted";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("missing.h5"), std::string::npos);
    }
    EXPECT_FALSE(std::filesystem::exists(o.out_path));
    EXPECT_FALSE(std::filesystem::exists(o.out_path + ".part"));
}

TEST(MethodSpecs, UnknownMethodOrParameterIsAClearError) {
    try {
        ParseMethodSpecs("identity,nosuch", {});
        FAIL();
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("unknown method 'nosuch'"), std::string::npos);
    }
    try {
        ParseMethodSpecs("identity", {{"identity", {{"bogus", 1}}}});
        FAIL();
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("unknown parameter 'bogus'"), std::string::npos);
    }
    EXPECT_THROW(ParseMethodSpecs("identity", {{"other", {}}}), std::invalid_argument);
    EXPECT_THROW(ParseMethodSpecs("", {}), std::invalid_argument);
}

// Issue 54 item 1: on a pair file of scale 150 the length parameters left at their defaults are
// multiplied (icp: correspondence distance 1 -> 150, Open3D's absolute RMSE stop 1e-6 -> 1.5e-4,
// the size rule's reference radius 0.6 -> 90, so `scale_rule` auto picks the unit pair's factor;
// ndt: transformation_epsilon, a squared length, 1e-6 -> 0.0225); a given value is used as is;
// scale 1 changes nothing. Expected values: the defaults times 150 (or 150^2), by hand.
TEST(MethodSpecs, LengthDefaultsFollowThePairFilesScaleAndGivenValuesWin) {
    const auto specs = ParseMethodSpecs("icp,ndt,identity", {});
    const auto mm = PairScaledSpecs(specs, 150.0);
    EXPECT_DOUBLE_EQ(mm[0].params["max_correspondence_distance"].get<double>(), 150.0);
    EXPECT_DOUBLE_EQ(mm[0].params["relative_rmse"].get<double>(), 1.5e-4);
    EXPECT_DOUBLE_EQ(mm[0].params["relative_fitness"].get<double>(), 1e-6);  // a ratio
    EXPECT_DOUBLE_EQ(mm[0].params["scale_rule_radius"].get<double>(), 0.6 * 150.0);
    EXPECT_EQ(mm[0].params["scale_rule"], "auto");
    EXPECT_DOUBLE_EQ(mm[1].params["transformation_epsilon"].get<double>(), 1e-6 * 150.0 * 150.0);
    EXPECT_DOUBLE_EQ(mm[1].params["resolution"].get<double>(), 0.25 * 150.0);
    EXPECT_DOUBLE_EQ(mm[1].params["scale_rule_radius"].get<double>(), 0.6 * 150.0);
    EXPECT_EQ(mm[2].params, specs[2].params);
    EXPECT_EQ(PairScaledSpecs(specs, 1.0)[0].params, specs[0].params);
    const auto given = PairScaledSpecs(
        ParseMethodSpecs("icp", {{"icp", {{"max_correspondence_distance", 1.0},
                                          {"relative_rmse", 1e-3},
                                          {"scale_rule", "preset"}}}}),
        150.0);
    EXPECT_DOUBLE_EQ(given[0].params["max_correspondence_distance"].get<double>(), 1.0);
    EXPECT_DOUBLE_EQ(given[0].params["relative_rmse"].get<double>(), 1e-3);
    EXPECT_EQ(given[0].params["scale_rule"], "preset");
    EXPECT_DOUBLE_EQ(given[0].params["scale_rule_radius"].get<double>(), 0.6 * 150.0);
}

TEST(ResultsFile, CorruptLineIsReportedWithFileAndLine) {
    const auto path = regbench::testing::TempPath("corrupt.jsonl");
    std::ofstream(path) << "{\"a\": 1}\n{broken\n";
    try {
        ReadJsonl(path.string());
        FAIL();
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(path.string() + ":2"), std::string::npos);
    }
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace regbench
