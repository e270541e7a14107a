// Method against method on common pairs (issue 41 item 1): `report --versus A,B`.
#include "reports/versus.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "reports/table.hpp"

namespace regbench {
namespace {

// Per-pair errors of two methods on pairs 0..11. Dyadic values, so every difference is exact.
// mae_r: one zero difference and 11 distinct |d| (the exact Wilcoxon table applies);
// mae_t: tied |d| (the normal approximation with the tie-corrected variance applies).
const std::vector<double> kMaeRA = {1.5, 2.25, 0.75, 3.0, 1.0,  4.5,
                                    2.0, 0.5,  1.25, 6.0, 2.75, 1.75};
const std::vector<double> kMaeRB = {2.0,   2.125,  1.5, 4.0,    1.0, 5.875,
                                    2.625, 1.5625, 1.0, 6.3125, 4.0, 3.5};
const std::vector<double> kMaeTA = {0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0, 5.5, 6.0};
const std::vector<double> kMaeTB = {0.75, 0.75, 1.75, 2.25, 3.0,  3.25,
                                    3.75, 3.5,  4.75, 5.75, 5.75, 6.0};

ResultRow Row(const std::string& method, std::size_t pair, double mae_r, double mae_t,
              const std::string& hash = "fnv1a64:00000000000000aa") {
    ResultRow r;
    r.pair = pair;
    r.method = method;
    r.data.pairs_file = "p.h5";
    r.data.content_hash = hash;
    r.metrics.mae_r = r.metrics.rre = mae_r;
    r.metrics.mae_t = r.metrics.rte = r.metrics.ccd = mae_t;
    return r;
}

/// Method "a" on pairs 0..11, "b" on 0..12 (pair 12 only b's: not compared), a third method.
std::vector<ResultRow> Rows() {
    std::vector<ResultRow> rows;
    for (std::size_t k = 0; k < kMaeRA.size(); ++k) {
        rows.push_back(Row("a", k, kMaeRA[k], kMaeTA[k]));
        rows.push_back(Row("b", k, kMaeRB[k], kMaeTB[k]));
        rows.push_back(Row("icp", k, 9.0, 9.0));
    }
    rows.push_back(Row("b", 12, 100.0, 100.0));
    rows[1].status = Status::kFailed;  // b on pair 0: counted, scored with its transform
    return rows;
}

TEST(Versus, DifferencesWilcoxonAndWinsAgreeWithScipy) {
    VersusOptions o;
    o.metrics = {"mae_r", "mae_t"};
    const std::vector<VersusResult> results = CompareMethods(Rows(), "a", "b", o);
    ASSERT_EQ(results.size(), 1u);
    const VersusResult& r = results[0];
    EXPECT_EQ(r.pairs_a, 12u);
    EXPECT_EQ(r.pairs_b, 13u);
    EXPECT_EQ(r.common, 12u);
    EXPECT_EQ(r.failed_a, 0u);
    EXPECT_EQ(r.failed_b, 1u);
    ASSERT_EQ(r.metrics.size(), 2u);
    // Expected values from scipy 1.10.1 (Debian's, /usr/bin/python3) and numpy on the arrays
    // above, d = a - b:
    //   d = a - b; d.mean() -> -0.6875; a.mean() -> 2.2708333333333335; b.mean() -> 2.9583...
    //   scipy.stats.wilcoxon(d[d != 0], method="exact") -> statistic 3.0, pvalue 0.0048828125
    //   (zeros dropped first: Wilcoxon's convention, zero_method="wilcox")
    //   (d < 0).sum(), (d == 0).sum(), (d > 0).sum() -> 9, 1, 2
    const VersusMetric& mr = r.metrics[0];
    EXPECT_EQ(mr.metric, "mae_r");
    EXPECT_EQ(mr.pairs, 12u);
    EXPECT_DOUBLE_EQ(mr.diff_mean, -0.6875);
    EXPECT_DOUBLE_EQ(mr.mean_a, 2.2708333333333335);
    EXPECT_DOUBLE_EQ(mr.mean_b, 2.9583333333333335);
    EXPECT_DOUBLE_EQ(mr.statistic, 3.0);
    EXPECT_NEAR(mr.p_value, 0.0048828125, 1e-12);
    EXPECT_EQ(mr.wins, 9u);
    EXPECT_EQ(mr.ties, 1u);
    EXPECT_EQ(mr.losses, 2u);
    EXPECT_LT(mr.ci_lo, mr.diff_mean);
    EXPECT_GT(mr.ci_hi, mr.diff_mean);
    EXPECT_LT(mr.ci_hi, 0.0);  // 9 of 11 non-zero differences favour a
    //   dt = a_t - b_t; scipy.stats.wilcoxon(dt, zero_method="wilcox", method="approx",
    //   correction=False) -> statistic 14.0, pvalue 0.07755419160303104; dt.mean() -> -0.1875
    const VersusMetric& mt = r.metrics[1];
    EXPECT_DOUBLE_EQ(mt.diff_mean, -0.1875);
    EXPECT_DOUBLE_EQ(mt.statistic, 14.0);
    EXPECT_NEAR(mt.p_value, 0.07755419160303104, 1e-12);
    EXPECT_EQ(mt.wins, 9u);
    EXPECT_EQ(mt.ties, 1u);
    EXPECT_EQ(mt.losses, 2u);
    // Swapping the methods flips the sign and the wins, keeps p.
    const VersusMetric swapped = CompareMethods(Rows(), "b", "a", o)[0].metrics[0];
    EXPECT_DOUBLE_EQ(swapped.diff_mean, 0.6875);
    EXPECT_EQ(swapped.wins, 2u);
    EXPECT_EQ(swapped.losses, 9u);
    EXPECT_NEAR(swapped.p_value, mr.p_value, 1e-15);
}

TEST(Versus, TableShowsEveryNumberAndTheData) {
    const Table t = VersusTable(CompareMethods(Rows(), "a", "b")[0]);
    const std::string md = TableToMarkdown(t);
    EXPECT_NE(md.find("a vs b"), std::string::npos) << md;
    EXPECT_NE(md.find("| mae_r | 12 |"), std::string::npos) << md;
    EXPECT_NE(md.find("0.0049"), std::string::npos) << md;  // the exact p above
    EXPECT_NE(md.find("| 9 | 1 | 2 |"), std::string::npos) << md;
    EXPECT_NE(md.find("12 pairs both ran"), std::string::npos) << md;
    EXPECT_NE(md.find("failed calls among them: a 0, b 1"), std::string::npos) << md;
    const std::string csv = TablesToCsv({t});
    EXPECT_NE(csv.find("diff_mean"), std::string::npos) << csv;  // the mean, a data column
}

TEST(Versus, RefusesWhatItCannotPair) {
    try {
        CompareMethods(Rows(), "a", "ogmm");
        FAIL() << "an absent method was accepted";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("no rows of method 'ogmm'; the results hold 'a', "
                                             "'b', 'icp'"),
                  std::string::npos)
            << e.what();
    }
    std::vector<ResultRow> apart = {Row("a", 0, 1, 1), Row("b", 0, 1, 1, "fnv1a64:bb")};
    EXPECT_THROW(CompareMethods(apart, "a", "b"), std::runtime_error);  // other pair files
    std::vector<ResultRow> twice = {Row("a", 0, 1, 1), Row("a", 0, 2, 2), Row("b", 0, 1, 1)};
    EXPECT_THROW(CompareMethods(twice, "a", "b"), std::runtime_error);  // two params sets
    EXPECT_THROW(CompareMethods(Rows(), "a", "a"), std::invalid_argument);
}

}  // namespace
}  // namespace regbench
