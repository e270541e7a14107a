// RunOptions::external_methods and check_interrupt: the hooks the Python module uses to run
// callables as methods (python/), tested here without Python.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "runners/runner.hpp"
#include "tests/testing/synthetic_pair_file.hpp"
#include "tests/testing/temp_dir_test.hpp"

namespace regbench {
namespace {

/// Returns a fixed translation; counts its calls in a shared counter.
class ShiftMethod final : public RegistrationMethod {
public:
    explicit ShiftMethod(std::atomic<int>* calls) : calls_(calls) {}
    std::string Name() const override { return "shift"; }
    nlohmann::json Params() const override { return {{"dx", 0.5}}; }

protected:
    AlignResult DoAlign(const PointCloud&, const PointCloud&, const AlignContext&) override {
        ++*calls_;
        AlignResult r;
        r.T_target_source(0, 3) = 0.5;
        r.iterations = 1;
        return r;
    }

private:
    std::atomic<int>* calls_;
};

class ExternalMethodTest : public testing::PairFileTest {
protected:
    ExternalMethodTest() : PairFileTest(4, 40, 10, 3) {}
    RunOptions Options(const std::string& out) {
        RunOptions o;
        o.pairs_path = pairs_;
        o.methods = ParseMethodSpecs("identity", {});
        o.methods.push_back(MethodSpec{"shift", {{"dx", 0.5}}});
        o.external_methods["shift"].create = [this] {
            return std::make_unique<ShiftMethod>(&calls_);
        };
        o.out_path = Path(out);
        o.progress = false;
        return o;
    }
    std::atomic<int> calls_{0};
};

TEST_F(ExternalMethodTest, RowsLikeRegisteredMethods) {
    RunOptions o = Options("r.jsonl");
    o.jobs = 2;
    const RunSummary s = RunBenchmark(o);
    EXPECT_EQ(s.rows_written, 8u);
    EXPECT_EQ(calls_.load(), 4);
    const auto rows = ReadJsonl(o.out_path);
    ASSERT_EQ(rows.size(), 8u);
    EXPECT_EQ(rows[1]["method"], "shift");
    EXPECT_EQ(rows[1]["params"], nlohmann::json({{"dx", 0.5}}));
    EXPECT_EQ(rows[1]["status"], "ok");
    EXPECT_EQ(rows[1]["transform"][0][3], 0.5);
    EXPECT_EQ(rows[1]["iterations"], 1);
}

TEST_F(ExternalMethodTest, IsolatedCallsRunTheForkHooks) {
    RunOptions o = Options("iso.jsonl");
    o.timeout_seconds = 30;
    std::atomic<int> prepared{0}, parented{0};
    o.external_methods["shift"].fork_hooks.prepare = [&prepared] { ++prepared; };
    o.external_methods["shift"].fork_hooks.parent = [&parented] { ++parented; };
    // The child hook runs in the child: exiting there leaves a child without a result.
    o.external_methods["shift"].fork_hooks.child = [] { ::_exit(3); };
    RunBenchmark(o);
    EXPECT_EQ(prepared.load(), 4);
    EXPECT_EQ(parented.load(), 4);
    for (const auto& row : ReadJsonl(o.out_path)) {
        EXPECT_EQ(row["status"], row["method"] == "shift" ? "crashed" : "ok") << row["method"];
    }
}

TEST_F(ExternalMethodTest, RegisteredNamesAreRefused) {
    RunOptions o = Options("clash.jsonl");
    o.external_methods["icp"] = o.external_methods["shift"];
    EXPECT_THROW(RunBenchmark(o), std::invalid_argument);
}

TEST_F(ExternalMethodTest, CheckInterruptEndsTheRunAndResumeFinishesIt) {
    RunOptions o = Options("stop.jsonl");
    int seen = 0;
    o.check_interrupt = [&seen] {
        if (++seen == 3) throw std::runtime_error("stop");
    };
    EXPECT_THROW(RunBenchmark(o), std::runtime_error);
    EXPECT_FALSE(std::filesystem::exists(o.out_path));
    EXPECT_EQ(ReadJsonl(o.out_path + ".part").size(), 2u);  // the third call's row is dropped
    o.check_interrupt = nullptr;
    o.resume = true;
    const RunSummary s = RunBenchmark(o);
    EXPECT_EQ(s.rows_skipped, 2u);
    EXPECT_EQ(s.rows_written, 6u);
    EXPECT_EQ(ReadJsonl(o.out_path).size(), 8u);
}

}  // namespace
}  // namespace regbench
