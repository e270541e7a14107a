// Method against method on common pairs (issue 41 item 1): `report --versus A,B`.
#include "reports/versus.hpp"

#include <gtest/gtest.h>

#include <cmath>
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
    rows[1].status = Status::kFailed;  // b on pair 0: counted (its metrics as the row has them)
    return rows;
}

TEST(Versus, DifferencesMeansAndWinsAgreeWithNumpyAndTheVerdictWithTheCi) {
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
    EXPECT_EQ(r.bootstrap_samples, 2000);
    ASSERT_EQ(r.metrics.size(), 2u);
    // Expected values from numpy on the arrays above (/usr/bin/python3), d = a - b:
    //   d.mean() -> -0.6875; a.mean() -> 2.2708333333333335; b.mean() -> 2.9583...
    //   (d < 0).sum(), (d == 0).sum(), (d > 0).sum() -> 9, 1, 2
    //   bootstrap of d.mean(), 400000 resamples (default_rng(0)): 2 min(P(m <= 0), P(m >= 0))
    //   = 1.5e-05, 95% percentile CI [-1.0260, -0.3490]
    const VersusMetric& mr = r.metrics[0];
    EXPECT_EQ(mr.metric, "mae_r");
    EXPECT_EQ(mr.pairs, 12u);
    EXPECT_DOUBLE_EQ(mr.diff_mean, -0.6875);
    EXPECT_DOUBLE_EQ(mr.mean_a, 2.2708333333333335);
    EXPECT_DOUBLE_EQ(mr.mean_b, 2.9583333333333335);
    EXPECT_EQ(mr.wins, 9u);
    EXPECT_EQ(mr.ties, 1u);
    EXPECT_EQ(mr.losses, 2u);
    EXPECT_NEAR(mr.ci_lo, -1.0260, 0.06);
    EXPECT_NEAR(mr.ci_hi, -0.3490, 0.06);
    EXPECT_LT(mr.p_value, 0.002);  // 2000 resamples: p is 0 or 0.001
    if (mr.p_value == 0.0) {  // no resampled mean reached 0: p < 1 / 2000
        EXPECT_NE(VersusVerdict(r, mr).find("], p < 0.0005)"), std::string::npos)
            << VersusVerdict(r, mr);
    }
    EXPECT_TRUE(mr.differs);
    EXPECT_EQ(VersusVerdict(r, mr).rfind("mae_r: a better than b (a - b = -0.6875, 95% CI [", 0),
              0u)
        << VersusVerdict(r, mr);
    //   dt = a_t - b_t: dt.mean() -> -0.1875; bootstrap (as above): p = 0.0552, CI
    //   [-0.3542, 0.0]: at the boundary, so with 2000 resamples either verdict may come; the
    //   verdict must follow the CI (Monte Carlo standard error of p: 0.0073).
    const VersusMetric& mt = r.metrics[1];
    EXPECT_DOUBLE_EQ(mt.diff_mean, -0.1875);
    EXPECT_EQ(mt.wins, 9u);
    EXPECT_EQ(mt.ties, 1u);
    EXPECT_EQ(mt.losses, 2u);
    EXPECT_NEAR(mt.p_value, 0.0552, 0.022);
    EXPECT_NEAR(mt.ci_lo, -0.3542, 0.06);
    EXPECT_NEAR(mt.ci_hi, 0.0, 0.03);
    EXPECT_EQ(mt.differs, mt.ci_hi < 0.0);
    EXPECT_EQ(mt.differs, mt.p_value <= 0.05);
    EXPECT_EQ(VersusVerdict(r, mt).rfind(mt.differs ? "mae_t: a better than b ("
                                                    : "mae_t: no difference shown between a and b (",
                                         0),
              0u)
        << VersusVerdict(r, mt);
    // Swapping the methods flips the sign, the CI and the wins, keeps the verdict's winner.
    const VersusResult swapped_r = CompareMethods(Rows(), "b", "a", o)[0];
    const VersusMetric& swapped = swapped_r.metrics[0];
    EXPECT_DOUBLE_EQ(swapped.diff_mean, 0.6875);
    EXPECT_EQ(swapped.wins, 2u);
    EXPECT_EQ(swapped.losses, 9u);
    EXPECT_GT(swapped.ci_lo, 0.0);
    EXPECT_EQ(VersusVerdict(swapped_r, swapped).rfind("mae_r: a better than b (b - a = 0.6875", 0),
              0u)
        << VersusVerdict(swapped_r, swapped);
}

TEST(Versus, OnePairGivesNoVerdict) {
    const std::vector<ResultRow> rows = {Row("a", 0, 1.0, 1.0), Row("b", 0, 3.0, 3.0)};
    const VersusResult r = CompareMethods(rows, "a", "b")[0];
    EXPECT_FALSE(r.metrics[0].differs);
    EXPECT_TRUE(std::isnan(r.metrics[0].p_value));
    EXPECT_EQ(VersusVerdict(r, r.metrics[0]),
              "mae_r: no verdict (1 common pair with a finite mae_r; a paired test needs two)");
}

TEST(Versus, TableShowsEveryNumberAndTheData) {
    const Table t = VersusTable(CompareMethods(Rows(), "a", "b")[0]);
    const std::string md = TableToMarkdown(t);
    EXPECT_NE(md.find("a vs b"), std::string::npos) << md;
    EXPECT_NE(md.find("| mae_r | 12 |"), std::string::npos) << md;
    EXPECT_NE(md.find("| 95% CI | p |"), std::string::npos) << md;
    EXPECT_EQ(md.find("Wilcoxon"), std::string::npos) << md;  // one procedure: the bootstrap
    // One verdict line per metric, under the table.
    for (const char* metric : {"mae_r", "mae_t", "ccd", "rre", "rte"}) {
        EXPECT_NE(md.find(std::string("\nVerdict ") + metric + ": "), std::string::npos) << md;
    }
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
