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

TEST(PairedBootstrap, PValueAndCiMatchTheExactBootstrapDistribution) {
    // Hand derivation (checked by enumerating itertools.product(d, repeat=3) in
    // /usr/bin/python3): the 27 equally likely resamples of d = {-2, 1, 4} have means with
    // #{mean <= 0} = 10 and #{mean >= 0} = 23, so the bootstrap p = 2 * 10 / 27 = 0.7407; the
    // extreme means -2 and 4 each have probability 1/27 = 3.7% > 2.5%, so the 95% CI is
    // [-2, 4]. With 2000 Monte Carlo resamples p has a standard error of 2 * sqrt(10/27 *
    // 17/27 / 2000) = 0.022: the tolerance is three of them.
    const PairedBootstrapTest t = PairedBootstrap({-2.0, 1.0, 4.0}, 2000, 11, StreamId("exact"));
    EXPECT_DOUBLE_EQ(t.mean, 1.0);
    EXPECT_NEAR(t.p_value, 20.0 / 27.0, 0.066);
    EXPECT_DOUBLE_EQ(t.lo, -2.0);
    EXPECT_DOUBLE_EQ(t.hi, 4.0);
    EXPECT_FALSE(t.differs);
    // By hand: a constant non-zero difference never resamples to 0 (p = 0 < 1/B, CI [c, c]);
    // all-zero differences always do (p = 1); one difference is no test (NaN, no verdict).
    const PairedBootstrapTest c = PairedBootstrap({0.5, 0.5, 0.5}, 2000, 11, StreamId("c"));
    EXPECT_DOUBLE_EQ(c.p_value, 0.0);
    EXPECT_DOUBLE_EQ(c.lo, 0.5);
    EXPECT_DOUBLE_EQ(c.hi, 0.5);
    EXPECT_TRUE(c.differs);
    const PairedBootstrapTest z = PairedBootstrap({0.0, 0.0, 0.0, 0.0}, 2000, 11, StreamId("z"));
    EXPECT_DOUBLE_EQ(z.p_value, 1.0);
    EXPECT_FALSE(z.differs);
    const PairedBootstrapTest one = PairedBootstrap({3.0}, 2000, 11, StreamId("one"));
    EXPECT_TRUE(std::isnan(one.p_value));
    EXPECT_TRUE(std::isnan(one.lo));
    EXPECT_FALSE(one.differs);
}

TEST(PairedBootstrap, SkewedDifferencesNoLongerGetASmallPWithACiAroundZero) {
    // Issue 54 item 5: 27 small negative differences and 3 large positive ones. The Wilcoxon
    // signed-rank test (which `report --versus` used to print beside a bootstrap CI of the mean)
    // calls this significant: scipy.stats.wilcoxon(d, method="approx", correction=False) ->
    // p = 0.002762407466545288, and WilcoxonSignedRank agrees, while the mean -1e-5 has a CI
    // well around 0. numpy, 400000 resamples (rng default_rng(0)): bootstrap p = 0.925, 95%
    // percentile CI [-0.00137, 0.00167].
    std::vector<double> d;
    for (int k = 1; k <= 27; ++k) d.push_back(-0.0001 * k);
    for (int k = 0; k < 3; ++k) d.push_back(0.0125);
    EXPECT_NEAR(WilcoxonSignedRank(d).p_value, 0.002762407466545288, 1e-12);
    const PairedBootstrapTest t = PairedBootstrap(d, 2000, kDefaultBootstrapSeed, StreamId("s"));
    EXPECT_NEAR(t.mean, -1e-5, 1e-15);
    EXPECT_NEAR(t.p_value, 0.925, 0.05);
    EXPECT_NEAR(t.lo, -0.00137, 0.0002);
    EXPECT_NEAR(t.hi, 0.00167, 0.0002);
    EXPECT_FALSE(t.differs);
}

TEST(PairedBootstrap, PAndCiAgreeForEverySampleAndResampleCount) {
    // The property the verdict rests on (no expected values needed): p <= 0.05 exactly when
    // the 95% CI excludes 0, whatever the shift (scanned across the boundary), skew, zeros,
    // ties and number of resamples (divisible by 40 or not, below 40).
    std::size_t significant = 0, not_significant = 0;
    for (const int b : {2000, 1000, 999, 1001, 41, 39, 7}) {
        for (int shift = -30; shift <= 30; ++shift) {
            std::vector<double> d;
            for (int i = 0; i < 24; ++i) {
                const double skewed = (i % 6 == 0) ? 2.5 : -0.4;  // mean 0 before the shift
                d.push_back(i % 5 == 0 ? 0.0 : skewed + 0.05 * shift + 0.01 * std::sin(i));
            }
            const PairedBootstrapTest t = PairedBootstrap(d, b, 5, StreamId(std::to_string(b)));
            const bool excludes = t.lo > 0.0 || t.hi < 0.0;
            EXPECT_EQ(t.p_value <= 0.05, excludes) << "B " << b << " shift " << shift;
            EXPECT_EQ(t.differs, excludes) << "B " << b << " shift " << shift;
            EXPECT_LE(t.lo, t.hi);
            (excludes ? significant : not_significant) += 1;
        }
    }
    EXPECT_GT(significant, 50u);  // the scan crosses the boundary on both sides
    EXPECT_GT(not_significant, 50u);
    // At the default 2000 resamples the CI is BootstrapMean's, the CI of every other table.
    std::vector<double> v;
    for (int i = 0; i < 25; ++i) v.push_back(std::cos(i) + 0.1 * i);
    const BootstrapCi ci = BootstrapMean(v, 2000, 3, StreamId("y"));
    const PairedBootstrapTest t = PairedBootstrap(v, 2000, 3, StreamId("y"));
    EXPECT_EQ(t.lo, ci.lo);
    EXPECT_EQ(t.hi, ci.hi);
}

}  // namespace
}  // namespace regbench

namespace regbench {
namespace {

TEST(SampleQuantile, MatchesNumpyLinear) {
    // numpy 1.24 (/usr/bin/python3): np.quantile(v, q), default method="linear".
    EXPECT_NEAR(SampleQuantile({0.1, 0.3, 0.2, 0.5, 0.4, 0.6, 0.7, 2.0}, 0.95),
                1.5449999999999993, 1e-12);
    EXPECT_NEAR(SampleQuantile({3, 1, 2}, 0.3), 1.6, 1e-12);
    EXPECT_NEAR(SampleQuantile({1, 2, 3, 4}, 0.95), 3.85, 1e-12);
    EXPECT_DOUBLE_EQ(SampleQuantile({5.0}, 0.95), 5.0);
    EXPECT_DOUBLE_EQ(SampleQuantile({4, 1, 3, 2}, 0.5), SampleMedian({4, 1, 3, 2}));
    EXPECT_TRUE(std::isnan(SampleQuantile({}, 0.5)));
}

}  // namespace
}  // namespace regbench
