// Fault isolation of one call (--timeout): a method that crashes, one that hangs and one that
// leaves without a result become crashed / timeout rows, and the calls after them still give
// complete rows. The misbehaving methods exist only in this test (the registry never has them).
#include "runners/isolated_call.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/file_lock.hpp"
#include "core/transform.hpp"
#include "runners/runner.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/synthetic.hpp"
#include "tests/testing/temp_dir_test.hpp"

namespace regbench {
namespace {

/// What TestMethod does inside DoAlign.
enum class Behaviour {
    kReturn,      ///< returns kAnswer
    kCrash,       ///< aborts (SIGABRT), as a library failing an assertion does
    kHang,        ///< never returns
    kExitSilent,  ///< the process ends without writing a result
    kSegfault,    ///< dies by SIGSEGV
    /// returns a failure whose message holds a byte that is not UTF-8 (0xFF), as a learned
    /// method did quoting a damaged checkpoint.json: serialising it threw in the child
    kBadUtf8Message,
};

/// A fixed rigid answer, written by hand: 30 degrees about z and a translation.
Transform Answer() {
    return MakeTransform(RotationFromEulerZyxDeg(30.0, 0.0, 0.0), {0.25, -0.5, 1.0});
}

class TestMethod : public RegistrationMethod {
public:
    explicit TestMethod(Behaviour b) : behaviour_(b) {}
    std::string Name() const override { return "test-method"; }
    nlohmann::json Params() const override { return nlohmann::json::object(); }

protected:
    AlignResult DoAlign(const PointCloud&, const PointCloud&, const AlignContext&) override {
        switch (behaviour_) {
            case Behaviour::kCrash:
                std::abort();
            case Behaviour::kHang:
                for (;;) pause();  // only SIGKILL from the parent ends this
            case Behaviour::kExitSilent:
                _exit(0);
            case Behaviour::kSegfault:
                std::raise(SIGSEGV);
                break;
            case Behaviour::kBadUtf8Message: {
                AlignResult failed;
                failed.status = AlignStatus::kFailed;
                failed.message = "checkpoint.json: unexpected byte \xFF";
                return failed;
            }
            case Behaviour::kReturn:
                break;
        }
        AlignResult r;
        r.T_target_source = Answer();
        r.iterations = 7;
        r.stop_reason = "converged";
        return r;
    }

private:
    Behaviour behaviour_;
};

TEST(AlignIsolated, CrashAndHangBecomeRowsAndTheOtherCallsComplete) {
    const Pair pair = testing::SyntheticPair(30, 5, Answer());
    MethodSpec spec{"test-method", nlohmann::json::object()};
    const std::vector<Behaviour> calls = {Behaviour::kReturn, Behaviour::kCrash, Behaviour::kHang,
                                          Behaviour::kExitSilent, Behaviour::kReturn};
    std::vector<ResultRow> rows;
    for (std::size_t k = 0; k < calls.size(); ++k) {
        TestMethod method(calls[k]);
        AlignContext context;
        context.pair_index = k;
        // 2 s bounds the hanging call; the others finish (or die) long before it.
        const CallOutcome outcome = AlignIsolated(method, pair, context, 2.0, 1);
        RowContext row_context;
        row_context.status = outcome.status;
        rows.push_back(MakeResultRow(k, pair, spec, outcome.result, row_context));
    }
    ASSERT_EQ(rows.size(), 5u);
    EXPECT_EQ(rows[1].status, Status::kCrashed);
    EXPECT_NE(rows[1].result.message.find("crashed with signal " + std::to_string(SIGABRT)),
              std::string::npos)
        << rows[1].result.message;
    EXPECT_EQ(rows[2].status, Status::kTimeout);
    EXPECT_NE(rows[2].result.message.find("exceeded timeout"), std::string::npos)
        << rows[2].result.message;
    EXPECT_EQ(rows[3].status, Status::kCrashed);
    EXPECT_NE(rows[3].result.message.find("child exited without a result"), std::string::npos)
        << rows[3].result.message;
    // Failed calls carry the identity fallback, never a half-made transform.
    for (const std::size_t k : {1, 2, 3}) {
        EXPECT_TRUE(rows[k].result.T_target_source == Transform::Identity()) << k;
    }
    // The calls before and after the bad ones are complete rows: the child's transform came
    // through the pipe bit for bit (JSON doubles round-trip), and the metrics against the
    // pair's ground truth (= the answer) are zero.
    for (const std::size_t k : {0, 4}) {
        EXPECT_EQ(rows[k].status, Status::kOk) << k;
        EXPECT_EQ(rows[k].result.iterations, 7) << k;
        EXPECT_EQ(rows[k].result.stop_reason, "converged") << k;
        EXPECT_TRUE(rows[k].result.T_target_source == Answer()) << k;
        EXPECT_NEAR(rows[k].metrics.rre, 0.0, 1e-5) << k;  // acos near 1: ~1e-6 deg
        EXPECT_NEAR(rows[k].metrics.rte, 0.0, 1e-12) << k;
    }
}

TEST(AlignInProcess, ReturnsTheMethodsResult) {
    const Pair pair = testing::SyntheticPair(30, 6, Answer());
    TestMethod method(Behaviour::kReturn);
    const CallOutcome outcome = AlignInProcess(method, pair, AlignContext{});
    EXPECT_EQ(outcome.status, Status::kOk);
    EXPECT_TRUE(outcome.result.T_target_source == Answer());
}

/// A forked child that still unwound into this test (the bug) stops in TearDown, before the
/// base TearDown would delete the parent's folder; the parent then sees the damage.
class ChildNeverOwnsTheLock : public testing::TempDirTest {
protected:
    void SetUp() override {
        testing::TempDirTest::SetUp();
        pid_ = ::getpid();
    }
    void TearDown() override {
        if (::getpid() != pid_) _exit(0);
        testing::TempDirTest::TearDown();
    }
    pid_t pid_ = 0;
};

// Issue 27, item 1. Expected values: the lock file is created by OutputLock in this process
// and only this process may remove it, so whatever the child does (throw while sending its
// result, segfault, be killed at the timeout) the lock file must still exist afterwards and a
// second OutputLock on the same output must still be refused; the child's outcome is what the
// parent's bookkeeping says (failed with the message / crashed / timeout).
TEST_F(ChildNeverOwnsTheLock, ThrowingCrashingAndTimedOutChildrenLeaveTheParentsLock) {
    const std::string out = Path("r.jsonl");
    const OutputLock lock(out);
    const Pair pair = testing::SyntheticPair(30, 5, Answer());
    const std::vector<std::pair<Behaviour, Status>> calls = {
        {Behaviour::kBadUtf8Message, Status::kFailed},
        {Behaviour::kSegfault, Status::kCrashed},
        {Behaviour::kHang, Status::kTimeout},
    };
    for (const auto& [behaviour, status] : calls) {
        TestMethod method(behaviour);
        const CallOutcome outcome = AlignIsolated(method, pair, AlignContext{}, 1.0, 1);
        EXPECT_EQ(outcome.status, status) << outcome.result.message;
        EXPECT_TRUE(std::filesystem::exists(lock.lock_path()))
            << "lock removed by the child of behaviour " << static_cast<int>(behaviour);
        EXPECT_NE(testing::ErrorOf([&] { OutputLock second(out); }), "")
            << "a second writer was accepted after behaviour " << static_cast<int>(behaviour);
    }
}

// The message with a non-UTF-8 byte arrives as a failed call whose message keeps its text.
TEST(AlignIsolated, NonUtf8MessageBecomesAFailedRow) {
    const Pair pair = testing::SyntheticPair(30, 5, Answer());
    TestMethod method(Behaviour::kBadUtf8Message);
    const CallOutcome outcome = AlignIsolated(method, pair, AlignContext{}, 5.0, 1);
    EXPECT_EQ(outcome.status, Status::kFailed);
    EXPECT_NE(outcome.result.message.find("checkpoint.json: unexpected byte"), std::string::npos)
        << outcome.result.message;
}

}  // namespace
}  // namespace regbench
