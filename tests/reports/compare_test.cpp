#include "reports/compare.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/testing/expect_throw.hpp"

namespace regbench {
namespace {

nlohmann::json Row(int pair, const std::string& method, double mae_r, const std::string& file) {
    return {{"pair", pair},
            {"method", method},
            {"status", "ok"},
            {"data", {{"pairs_file", file}}},
            {"metrics",
             {{"mae_r", mae_r},
              {"mae_t", 0.01 * mae_r},
              {"ccd", 0.05},
              {"rre", 2 * mae_r},
              {"rte", 0.02 * mae_r}}}};
}

/// 50 pairs of two methods with errors spread over 1-20 degrees (a fixed pseudo-random walk).
std::vector<nlohmann::json> Baseline(const std::string& file = "p.h5") {
    std::vector<nlohmann::json> rows;
    for (int k = 0; k < 50; ++k) {
        rows.push_back(Row(k, "icp", 1.0 + std::fmod(k * 7.31, 19.0), file));
        rows.push_back(Row(k, "cpd", 2.0 + std::fmod(k * 3.77, 11.0), file));
    }
    return rows;
}

TEST(Compare, FlagsATwoDegreeRegressionOnFiftyPairs) {
    auto candidate = Baseline();
    for (auto& r : candidate) {
        if (r["method"] != "cpd") continue;
        // +2 degrees with +-0.5 jitter, so not every difference is equal.
        const double jitter = 0.5 * std::sin(r["pair"].get<int>() * 1.3);
        r["metrics"]["mae_r"] = r["metrics"]["mae_r"].get<double>() + 2.0 + jitter;
    }
    const CompareResult res = CompareResults(Baseline(), candidate, CompareOptions{});
    EXPECT_EQ(res.matched_rows, 100u);
    EXPECT_TRUE(res.Regressed());
    bool found = false;
    for (const auto& c : res.changes) {
        if (c.method == "cpd" && c.metric == "mae_r") {
            found = true;
            EXPECT_TRUE(c.regression);
            EXPECT_NEAR(c.diff_mean, 2.0, 0.2);
            EXPECT_LT(c.ci_lo, c.diff_mean);
            EXPECT_GT(c.ci_lo, 1.5);
            // All 50 differences positive and untied: exact p = 2 / 2^50.
            EXPECT_NEAR(c.p_value, 2.0 / std::ldexp(1.0, 50), 1e-20);
        } else {
            EXPECT_FALSE(c.regression) << c.method << " " << c.metric;
        }
    }
    EXPECT_TRUE(found);
    const std::string md = FormatCompareMarkdown(res, CompareOptions{});
    EXPECT_NE(md.find("| cpd | mae_r | 50 |"), std::string::npos) << md;
    EXPECT_NE(md.find("FAIL"), std::string::npos);
    EXPECT_EQ(md.find("| icp |"), std::string::npos) << md;
}

TEST(Compare, UnchangedRunPasses) {
    const CompareResult res = CompareResults(Baseline(), Baseline(), CompareOptions{});
    EXPECT_FALSE(res.Regressed());
    for (const auto& c : res.changes) {
        EXPECT_DOUBLE_EQ(c.diff_mean, 0.0);
        EXPECT_FALSE(c.significant);
    }
    EXPECT_NE(FormatCompareMarkdown(res, CompareOptions{}).find("PASS"), std::string::npos);
}

TEST(Compare, ToleranceAbsorbsASmallWorsening) {
    auto candidate = Baseline();
    for (auto& r : candidate) r["metrics"]["mae_r"] = r["metrics"]["mae_r"].get<double>() + 0.3;
    CompareOptions o;
    ParseTolerance("mae_r=0.5", &o);
    const CompareResult loose = CompareResults(Baseline(), candidate, o);
    EXPECT_FALSE(loose.Regressed());
    bool worse = false;
    for (const auto& c : loose.changes) worse |= c.worse;
    EXPECT_TRUE(worse);  // still reported as significantly worse, only within tolerance
    EXPECT_TRUE(CompareResults(Baseline(), candidate, CompareOptions{}).Regressed());
}

TEST(Compare, ImprovementIsNotARegression) {
    auto candidate = Baseline();
    for (auto& r : candidate) r["metrics"]["rre"] = r["metrics"]["rre"].get<double>() * 0.5;
    const CompareResult res = CompareResults(Baseline(), candidate, CompareOptions{});
    EXPECT_FALSE(res.Regressed());
    std::size_t better = 0;
    for (const auto& c : res.changes) better += c.significant && !c.worse;
    EXPECT_EQ(better, 2u);  // rre of both methods
}

TEST(Compare, MismatchedPairFilesAreRefusedNamingBoth) {
    testing::ExpectThrowsWith<std::runtime_error>(
        [] {
            CompareResults(Baseline("tab1_same.h5"), Baseline("tab1_cross.h5"), CompareOptions{});
        },
        "tab1_same.h5", "tab1_cross.h5");
}

TEST(Compare, RepeatedRowIsAnError) {
    auto base = Baseline();
    base.push_back(base.front());
    EXPECT_THROW(CompareResults(base, Baseline(), CompareOptions{}), std::runtime_error);
}

TEST(Compare, ToleranceParsing) {
    CompareOptions o;
    ParseTolerance("0.25", &o);
    EXPECT_DOUBLE_EQ(o.default_tolerance, 0.25);
    ParseTolerance("mae_r=1,ccd=0.002", &o);
    EXPECT_DOUBLE_EQ(o.tolerance.at("mae_r"), 1.0);
    EXPECT_DOUBLE_EQ(o.tolerance.at("ccd"), 0.002);
    EXPECT_THROW(ParseTolerance("mae_r=abc", &o), std::invalid_argument);
    EXPECT_THROW(ParseTolerance("-1", &o), std::invalid_argument);
}

}  // namespace
}  // namespace regbench
