#include "reports/statistics.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace regbench {
namespace {

// Expected values from scipy 1.10.1 (/usr/bin/python3):
//   scipy.stats.wilcoxon(d, method=...) -> (statistic, pvalue)

TEST(Wilcoxon, ExactMatchesScipyOnTenDifferences) {
    // wilcoxon(a, method='exact') = (11.0, 0.10546875)
    const std::vector<double> a = {0.31, -1.2, 2.5, 0.8, -0.05, 1.7, 3.1, -0.6, 0.9, 1.15};
    const WilcoxonResult r = WilcoxonSignedRank(a);
    EXPECT_EQ(r.method, WilcoxonMethod::kExact);
    EXPECT_EQ(r.n, 10u);
    EXPECT_DOUBLE_EQ(r.statistic, 11.0);
    EXPECT_NEAR(r.p_value, 0.10546875, 1e-15);
}

TEST(Wilcoxon, ExactAllPositiveFive) {
    // wilcoxon([1,2,3,4,5]) = (0.0, 0.0625): 2 * (1 / 2^5).
    const WilcoxonResult r = WilcoxonSignedRank({1.0, 2.0, 3.0, 4.0, 5.0});
    EXPECT_DOUBLE_EQ(r.statistic, 0.0);
    EXPECT_NEAR(r.p_value, 0.0625, 1e-15);
}

TEST(Wilcoxon, NormalApproximationMatchesScipyOnSixtyWithZeroAndTies) {
    // b = [((i*37) % 61 - 25) / 10.0 + 0.4 for i in range(60)] (one zero, tied magnitudes);
    // wilcoxon(b, method='approx') = (431.0, 0.0006104519750996097)
    std::vector<double> b;
    for (int i = 0; i < 60; ++i) b.push_back(((i * 37) % 61 - 25) / 10.0 + 0.4);
    const WilcoxonResult r = WilcoxonSignedRank(b);
    EXPECT_EQ(r.method, WilcoxonMethod::kNormal);
    EXPECT_EQ(r.n, 59u);
    EXPECT_DOUBLE_EQ(r.statistic, 431.0);
    EXPECT_NEAR(r.p_value, 0.0006104519750996097, 1e-12);
}

TEST(Wilcoxon, TiesUseTieCorrectedNormal) {
    // wilcoxon(c, method='approx') = (15.0, 0.05866024364167236)
    const std::vector<double> c = {1, 1, -1, 2, 2, 2, 3, -3, 0.5, 4, 4, -0.5};
    const WilcoxonResult r = WilcoxonSignedRank(c);
    EXPECT_EQ(r.method, WilcoxonMethod::kNormal);
    EXPECT_DOUBLE_EQ(r.statistic, 15.0);
    EXPECT_NEAR(r.p_value, 0.05866024364167236, 1e-12);
}

TEST(Wilcoxon, AllZeroDifferencesGivePOne) {
    const WilcoxonResult r = WilcoxonSignedRank({0.0, 0.0, 0.0});
    EXPECT_EQ(r.n, 0u);
    EXPECT_DOUBLE_EQ(r.p_value, 1.0);
}

TEST(Statistics, MeanMedianStdByHand) {
    // numpy: mean 2.5, median 2.5, std(ddof=1) = sqrt(5/3).
    const std::vector<double> v = {4.0, 1.0, 3.0, 2.0};
    EXPECT_DOUBLE_EQ(SampleMean(v), 2.5);
    EXPECT_DOUBLE_EQ(SampleMedian(v), 2.5);
    EXPECT_NEAR(SampleStd(v), std::sqrt(5.0 / 3.0), 1e-15);
    EXPECT_DOUBLE_EQ(SampleMedian({5.0, 1.0, 3.0}), 3.0);
    EXPECT_TRUE(std::isnan(SampleMean({})));
}

TEST(Statistics, BootstrapIsSeededAndBracketsTheMean) {
    std::vector<double> v;
    for (int i = 0; i < 40; ++i) v.push_back(std::sin(i) * 3.0 + 10.0);
    const BootstrapCi a = BootstrapMean(v, 500, 7, StreamId("x"));
    const BootstrapCi b = BootstrapMean(v, 500, 7, StreamId("x"));
    const BootstrapCi c = BootstrapMean(v, 500, 8, StreamId("x"));
    EXPECT_DOUBLE_EQ(a.lo, b.lo);
    EXPECT_DOUBLE_EQ(a.hi, b.hi);
    EXPECT_LT(a.lo, a.mean);
    EXPECT_GT(a.hi, a.mean);
    EXPECT_NE(a.lo, c.lo);
    // Standard error of the mean is std/sqrt(40) ~ 0.34: the 95% CI spans roughly +-0.66.
    EXPECT_NEAR(a.hi - a.lo, 2 * 1.96 * SampleStd(v) / std::sqrt(40.0), 0.3);
}

}  // namespace
}  // namespace regbench
