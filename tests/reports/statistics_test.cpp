#include "reports/statistics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

namespace regbench {
namespace {

// Expected values from scipy 1.10.1 (/usr/bin/python3):
//   scipy.stats.wilcoxon(d, method=...) -> (statistic, pvalue)

/// b = [((i*37) % 61 - 25) / 10.0 + 0.4 for i in range(60)]: one zero, tied magnitudes.
std::vector<double> SixtyWithZeroAndTies() {
    std::vector<double> b;
    for (int i = 0; i < 60; ++i) b.push_back(((i * 37) % 61 - 25) / 10.0 + 0.4);
    return b;
}

struct WilcoxonCase {
    const char* name;
    std::vector<double> sample;
    WilcoxonMethod method;
    std::size_t n;  ///< nonzero differences
    double statistic, p_value;
    double p_tol;
    const char* source;  ///< where the expected statistic and p-value come from
};

TEST(Wilcoxon, MatchesScipy) {
    const WilcoxonCase cases[] = {
        {"exact on ten differences",
         {0.31, -1.2, 2.5, 0.8, -0.05, 1.7, 3.1, -0.6, 0.9, 1.15},
         WilcoxonMethod::kExact,
         10,
         11.0,
         0.10546875,
         1e-15,
         "wilcoxon(a, method='exact') = (11.0, 0.10546875)"},
        {"exact, all five positive",
         {1.0, 2.0, 3.0, 4.0, 5.0},
         WilcoxonMethod::kExact,
         5,
         0.0,
         0.0625,
         1e-15,
         "wilcoxon([1,2,3,4,5]) = (0.0, 0.0625): 2 * (1 / 2^5)"},
        {"normal approximation on sixty with a zero and ties", SixtyWithZeroAndTies(),
         WilcoxonMethod::kNormal, 59, 431.0, 0.0006104519750996097, 1e-12,
         "wilcoxon(b, method='approx') = (431.0, 0.0006104519750996097)"},
        {"ties use the tie-corrected normal",
         {1, 1, -1, 2, 2, 2, 3, -3, 0.5, 4, 4, -0.5},
         WilcoxonMethod::kNormal,
         12,
         15.0,
         0.05866024364167236,
         1e-12,
         "wilcoxon(c, method='approx') = (15.0, 0.05866024364167236)"},
    };
    for (const WilcoxonCase& c : cases) {
        SCOPED_TRACE(std::string(c.name) + "; scipy: " + c.source);
        const WilcoxonResult r = WilcoxonSignedRank(c.sample);
        EXPECT_EQ(r.method, c.method);
        EXPECT_EQ(r.n, c.n);
        EXPECT_DOUBLE_EQ(r.statistic, c.statistic);
        EXPECT_NEAR(r.p_value, c.p_value, c.p_tol);
    }
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

TEST(Statistics, NearestRankQuantileIsNumpysNearest) {
    // /usr/bin/python3, numpy 1.24.2: np.percentile(np.arange(B), [2.5, 97.5], method="nearest")
    //   B = 1000 -> [25, 974]; B = 2000 -> [50, 1949]; B = 21 -> [0, 20] (halves to even:
    //   0.025 * 20 = 0.5 -> 0, 0.975 * 20 = 19.5 -> 20).
    for (const auto& [n, lo, hi] :
         {std::tuple<int, double, double>{1000, 25, 974}, {2000, 50, 1949}, {21, 0, 20}}) {
        std::vector<double> v(static_cast<std::size_t>(n));
        for (int i = 0; i < n; ++i) v[static_cast<std::size_t>(i)] = i;
        EXPECT_DOUBLE_EQ(NearestRankQuantile(v, 0.025), lo) << n;
        EXPECT_DOUBLE_EQ(NearestRankQuantile(v, 0.975), hi) << n;
    }
    EXPECT_TRUE(std::isnan(NearestRankQuantile({}, 0.5)));
}

TEST(Statistics, BootstrapCiIsTheNearestRankOfTheResampledMeans) {
    std::vector<double> v;
    for (int i = 0; i < 25; ++i) v.push_back(std::cos(i) + 0.1 * i);
    const std::vector<double> means = SortedBootstrapMeans(v, 1000, 3, StreamId("y"));
    ASSERT_EQ(means.size(), 1000u);
    ASSERT_TRUE(std::is_sorted(means.begin(), means.end()));
    const BootstrapCi ci = BootstrapMean(v, 1000, 3, StreamId("y"));
    // Index 25 and 974 of 0..999: 25 resampled means below lo's index, 25 above hi's.
    EXPECT_EQ(ci.lo, means[25]);
    EXPECT_EQ(ci.hi, means[974]);
    EXPECT_DOUBLE_EQ(ci.mean, SampleMean(v));
    // Fewer than two values: no interval.
    const BootstrapCi one = BootstrapMean({2.5}, 1000, 3, StreamId("y"));
    EXPECT_DOUBLE_EQ(one.lo, 2.5);
    EXPECT_DOUBLE_EQ(one.hi, 2.5);
}

TEST(Statistics, WilsonIntervalMatchesScipy) {
    // scipy 1.10.1: binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson").
    struct Case {
        std::size_t k, n;
        double lo, hi;
    };
    for (const Case& c : {Case{4, 100, 0.01566330399154762, 0.0983707143588792},
                          Case{0, 20, 0.0, 0.16112515805281935},
                          Case{11, 100, 0.06254196357064568, 0.18631296503080313},
                          Case{3, 3, 0.4385029682449546, 1.0}}) {
        const BootstrapCi w = WilsonInterval(c.k, c.n);
        EXPECT_DOUBLE_EQ(w.mean, static_cast<double>(c.k) / static_cast<double>(c.n));
        EXPECT_NEAR(w.lo, c.lo, 1e-12) << c.k << "/" << c.n;
        EXPECT_NEAR(w.hi, c.hi, 1e-12) << c.k << "/" << c.n;
    }
    EXPECT_TRUE(std::isnan(WilsonInterval(0, 0).lo));
}

}  // namespace
}  // namespace regbench
