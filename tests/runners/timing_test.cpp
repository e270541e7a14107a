// CPU time beside wall time: rows carry cpu_seconds and the machine's load; the summary for the
// reports flags oversubscribed runs.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/cpu_time.hpp"
#include "runners/runner.hpp"
#include "runners/timing_summary.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/synthetic_pair_file.hpp"

namespace regbench {
namespace {

TEST(CpuTime, ThreadClockAdvancesWithWorkAndStopwatchPicksItsScope) {
    const double before = ThreadCpuSeconds();
    volatile double sink = 0.0;
    for (int i = 0; i < 2000000; ++i) sink = sink + std::sqrt(static_cast<double>(i));
    EXPECT_GT(ThreadCpuSeconds(), before);
    EXPECT_GE(ProcessCpuSeconds(), ThreadCpuSeconds() - 1e-3);  // the process includes us
    EXPECT_STREQ(CpuStopwatch(1).Scope(), "thread");
    EXPECT_STREQ(CpuStopwatch(2).Scope(), "process");
    const MachineLoad load = ReadMachineLoad();
    EXPECT_GE(load.cores, 1);
    EXPECT_GE(load.load1, 0.0);  // /proc/loadavg exists on Linux
    EXPECT_LE(load.FreeCores(), load.cores);
}

TEST(RunnerTiming, EveryOkRowHasPositiveCpuSecondsAndTheMachineLoad) {
    const auto dir = regbench::testing::TempPath("runner_timing");
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    RunOptions o;
    o.pairs_path = (dir / "pairs.h5").string();
    testing::WriteSyntheticPairFile(o.pairs_path, 3, 200, 10, 3, [](int k) {
        return MakeTransform(RotationFromEulerZyxDeg(5.0 * k, 0, 0), {0.01, 0, 0});
    });
    o.methods = ParseMethodSpecs("cpd,icp", {});
    o.progress = false;
    for (const double timeout : {0.0, 60.0}) {  // in process, and in an isolated child
        o.timeout_seconds = timeout;
        o.out_path = (dir / ("r" + std::to_string(static_cast<int>(timeout)) + ".jsonl")).string();
        RunBenchmark(o);
        const auto rows = ReadJsonl(o.out_path);
        ASSERT_EQ(rows.size(), 6u);
        for (const auto& row : rows) {
            ASSERT_EQ(row["status"], "ok") << row.dump();
            EXPECT_GT(row["cpu_seconds"].get<double>(), 0.0) << row["method"];
            EXPECT_EQ(row["cpu_scope"], "thread");
            ASSERT_TRUE(row.contains("machine"));
            EXPECT_EQ(row["machine"]["loadavg"].size(), 3u);
            EXPECT_GE(row["machine"]["cores"].get<int>(), 1);
            // Timing provenance (issue 54): the CPU model and the libraries' versions.
            EXPECT_FALSE(row["machine"]["cpu"].get<std::string>().empty());
            for (const char* lib : {"eigen", "open3d", "libtorch", "blas"}) {
                EXPECT_FALSE(row["machine"]["libraries"][lib].get<std::string>().empty()) << lib;
            }
        }
    }
    std::filesystem::remove_all(dir);
}

ResultRow Row(double wall, double cpu, Status status = Status::kOk) {
    ResultRow row;
    row.status = status;
    row.result.seconds = wall;
    row.result.cpu_seconds = cpu;
    row.machine = {{"loadavg", {3.0, 2.0, 1.0}}};
    return row;
}

TEST(TimingSummary, RatioOfMeansAndWarningAboveThreshold) {
    // Hand values: wall 0.2 + 0.4 = 0.6, CPU 0.1 + 0.2 = 0.3 -> ratio 2; the failed row and the
    // row without cpu_seconds are skipped.
    ResultRow old_row;  // written before cpu_seconds existed: reads as 0
    old_row.result.seconds = 5.0;
    std::vector<ResultRow> rows = {Row(0.2, 0.1), Row(0.4, 0.2), Row(9.0, 1.0, Status::kFailed),
                                   old_row};
    const TimingSummary s = SummariseTiming(rows);
    EXPECT_EQ(s.rows, 2u);
    EXPECT_DOUBLE_EQ(s.mean_wall_seconds, 0.3);
    EXPECT_DOUBLE_EQ(s.mean_cpu_seconds, 0.15);
    EXPECT_DOUBLE_EQ(s.wall_cpu_ratio, 2.0);
    EXPECT_TRUE(s.oversubscribed);
    EXPECT_NE(s.warning.find("2.00"), std::string::npos) << s.warning;
    EXPECT_NE(s.warning.find("load at run start: 3.0"), std::string::npos) << s.warning;

    // 1.2 is below the 1.3 threshold: no warning.
    const TimingSummary calm = SummariseTiming({Row(0.12, 0.1)});
    EXPECT_FALSE(calm.oversubscribed);
    EXPECT_TRUE(calm.warning.empty());
    EXPECT_EQ(SummariseTiming({}).rows, 0u);
}

}  // namespace
}  // namespace regbench
