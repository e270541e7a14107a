// The regbench binary sets OMP_WAIT_POLICY=PASSIVE by re-executing itself (libgomp reads the
// variable before main); these tests run the built binary as a child process.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

#include "core/transform.hpp"
#include "runners/runner.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/synthetic_pair_file.hpp"

namespace regbench {
namespace {

/// Runs a shell command, returning its stdout+stderr; fails the test on a non-zero exit.
std::string Shell(const std::string& command) {
    std::string output;
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    if (pipe == nullptr) {
        ADD_FAILURE() << "popen failed: " << command;
        return output;
    }
    std::array<char, 4096> buf{};
    while (fgets(buf.data(), buf.size(), pipe) != nullptr) output += buf.data();
    const int status = pclose(pipe);
    EXPECT_EQ(status, 0) << command << "\n" << output;
    return output;
}

const std::string kExe = REGBENCH_EXE;

TEST(OmpWaitPolicy, UnsetBecomesPassiveInsideTheBinary) {
    // libgomp prints its effective settings at start-up with OMP_DISPLAY_ENV=true.
    const std::string unset =
        Shell("env -u OMP_WAIT_POLICY OMP_DISPLAY_ENV=true " + kExe + " methods");
    EXPECT_NE(unset.find("OMP_WAIT_POLICY = 'PASSIVE'"), std::string::npos) << unset;
    // An explicit choice is kept.
    const std::string active =
        Shell("env OMP_WAIT_POLICY=ACTIVE OMP_DISPLAY_ENV=true " + kExe + " methods");
    EXPECT_NE(active.find("OMP_WAIT_POLICY = 'ACTIVE'"), std::string::npos) << active;
}

TEST(OmpWaitPolicy, ThreadedRunsGiveIdenticalTransformsUnderEveryPolicy) {
    const auto dir = regbench::testing::TempPath("omp_wait_policy");
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const std::string pairs = (dir / "pairs.h5").string();
    testing::WriteSyntheticPairFile(pairs, 3, 400, 20, 5, [](int k) {
        return MakeTransform(RotationFromEulerZyxDeg(10.0 * k, 5, 0), {0.05, 0, 0});
    });
    std::vector<std::vector<nlohmann::json>> runs;
    for (const std::string env :
         {"env -u OMP_WAIT_POLICY", "env OMP_WAIT_POLICY=PASSIVE", "env OMP_WAIT_POLICY=ACTIVE"}) {
        const std::string out = (dir / ("r" + std::to_string(runs.size()) + ".jsonl")).string();
        Shell(env + " " + kExe + " run -q --threads 2 --methods cpd,icp,gmmreg --pairs " + pairs +
              " --out " + out);
        runs.push_back(ReadJsonl(out));
    }
    ASSERT_EQ(runs[0].size(), 9u);
    for (std::size_t r = 1; r < runs.size(); ++r) {
        ASSERT_EQ(runs[r].size(), runs[0].size());
        for (std::size_t k = 0; k < runs[0].size(); ++k) {
            EXPECT_EQ(runs[r][k]["status"], "ok");
            EXPECT_EQ(runs[r][k]["threads"], 2);
            // The wait policy only changes how idle threads wait. regbench's own kernels sum in
            // a fixed order whatever the threads do: bitwise equal. Open3D's ICP reduces with
            // OpenMP in scheduling order, so its last bits vary from run to run under any one
            // policy: equal to 1e-9.
            const auto& a = runs[r][k]["transform"];
            const auto& b = runs[0][k]["transform"];
            if (runs[0][k]["method"] == "icp") {
                for (int i = 0; i < 4; ++i) {
                    for (int j = 0; j < 4; ++j) {
                        EXPECT_NEAR(a[i][j].get<double>(), b[i][j].get<double>(), 1e-9)
                            << "icp pair " << runs[0][k]["pair"];
                    }
                }
            } else {
                EXPECT_EQ(a, b) << runs[0][k]["method"] << " pair " << runs[0][k]["pair"];
            }
        }
    }
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace regbench
