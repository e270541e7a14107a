// Every local and global baseline recovers a known motion on a clean complete pair (target =
// T_gt(source) point for point): one table of {method, angle, tolerance} instead of one
// near-identical test per method. Method-specific behaviour stays in each method's own file.
#include <gtest/gtest.h>

#include <optional>
#include <ostream>
#include <string>

#include "runners/registry.hpp"
#include "tests/baselines/registration_fixtures.hpp"

namespace regbench {
namespace {

using testing::AlignOk;
using testing::CleanCompletePair;
using testing::RreDeg;

struct RecoveryCase {
    const char* method;
    double angle_deg;  ///< rotation of the pair about its oblique axis
    double rre_tol_deg;
    /// What else the method reports on this pair: an exact iteration count, a lower bound on
    /// it, or its stop reason (unset: not checked).
    std::optional<int> iterations;
    std::optional<int> min_iterations;
    std::optional<std::string> stop_reason;
};

// gtest prints the case in a failing test's name line.
std::ostream& operator<<(std::ostream& os, const RecoveryCase& c) {
    return os << c.method << " at " << c.angle_deg << " deg";
}

class CleanCompletePairRecovery : public ::testing::TestWithParam<RecoveryCase> {};

TEST_P(CleanCompletePairRecovery, RotationErrorWithinTolerance) {
    const RecoveryCase& c = GetParam();
    SCOPED_TRACE(c.method);
    const auto pair = CleanCompletePair(c.angle_deg);
    const AlignResult r = AlignOk(c.method, pair);
    EXPECT_LT(RreDeg(pair, r.T_target_source), c.rre_tol_deg);
    if (c.iterations) {
        EXPECT_EQ(r.iterations, *c.iterations);
    }
    if (c.min_iterations) {
        EXPECT_GE(r.iterations, *c.min_iterations);
    }
    if (c.stop_reason) {
        EXPECT_EQ(r.stop_reason, *c.stop_reason);
    }
}

INSTANTIATE_TEST_SUITE_P(
    Methods, CleanCompletePairRecovery,
    ::testing::Values(
        // Local methods from a small motion: 0.5 degrees for the ICPs and GICP, 1 for NDT's
        // voxel approximation. ICP must iterate (a single step leaves more than 0.5 degrees,
        // icp_test MaxIterationsIsApplied); GICP must stop by convergence.
        RecoveryCase{"icp", 10.0, 0.5, std::nullopt, 2, std::nullopt},
        RecoveryCase{"icp-pl", 10.0, 0.5, std::nullopt, std::nullopt, std::nullopt},
        RecoveryCase{"gicp", 10.0, 0.5, std::nullopt, std::nullopt, "converged"},
        RecoveryCase{"ndt", 5.0, 1.0, std::nullopt, std::nullopt, std::nullopt},
        // Global: no initial guess needed, identical points give identical FPFH descriptors;
        // FGR runs its fixed 64 iterations.
        RecoveryCase{"fgr", 60.0, 1.0, 64, std::nullopt, std::nullopt}),
    [](const ::testing::TestParamInfo<RecoveryCase>& info) {
        std::string name = info.param.method;
        for (char& ch : name) {
            if (ch == '-') ch = '_';
        }
        return name;
    });

}  // namespace
}  // namespace regbench
