#include "reports/breakdown.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>

namespace regbench {
namespace {

ResultRow Row(const std::string& method, double mae_r, double mae_t, const std::string& category,
              std::optional<double> overlap, Status status = Status::kOk) {
    ResultRow r;
    r.method = method;
    r.status = status;
    r.category = category;
    r.source_overlap_ratio = overlap;
    if (overlap) r.target_overlap_ratio = *overlap + 0.05;
    r.metrics.mae_r = mae_r;
    r.metrics.mae_t = mae_t;
    r.metrics.ccd = 0.05;
    r.metrics.rre = 2 * mae_r;
    r.metrics.rte = 2 * mae_t;
    return r;
}

std::vector<ResultRow> Rows() {
    return {Row("a", 0.5, 0.005, "chair", 0.55), Row("a", 3.0, 0.02, "chair", 0.75),
            Row("a", 8.0, 0.5, "plane", 0.75, Status::kFailed), Row("a", 12.0, 0.05, "plane", 0.95),
            Row("b", 1.5, 0.2, "chair", 0.55, Status::kTimeout)};
}

TEST(Breakdown, DistributionByHand) {
    const Table t = DistributionTable(Rows(), BreakdownOptions{});
    ASSERT_EQ(t.rows.size(), 2u);
    const TableRow& a = t.rows[0];
    // mae_r of a: 0.5, 3, 8, 12 -> mean 5.875, median 5.5, np.std(ddof=1) = 5.137687547266117
    EXPECT_DOUBLE_EQ(a.Get("pairs").value, 4.0);
    EXPECT_DOUBLE_EQ(a.Get("mae_r.mean").value, 5.875);
    EXPECT_DOUBLE_EQ(a.Get("mae_r.median").value, 5.5);
    EXPECT_NEAR(a.Get("mae_r.std").value, 5.137687547266117, 1e-12);
    EXPECT_GT(a.Get("mae_r.mean").HalfWidth(), 0.0);
}

TEST(Breakdown, StatusCountsAndNullMetrics) {
    auto rows = Rows();
    // A crashed call whose mae_r is null in the JSONL (NaN in the row): a null metric.
    rows.push_back(Row("b", std::nan(""), 0.1, "chair", 0.55, Status::kCrashed));
    rows.push_back(Row("b", 1.0, 0.1, "chair", 0.55, Status::kMissing));  // `score`: other
    const Table t = StatusTable(rows);
    EXPECT_DOUBLE_EQ(t.rows[0].Get("ok").value, 3.0);
    EXPECT_DOUBLE_EQ(t.rows[0].Get("failed").value, 1.0);
    EXPECT_DOUBLE_EQ(t.rows[1].Get("timeout").value, 1.0);
    EXPECT_DOUBLE_EQ(t.rows[1].Get("crashed").value, 1.0);
    EXPECT_DOUBLE_EQ(t.rows[1].Get("other").value, 1.0);
    EXPECT_DOUBLE_EQ(t.rows[1].Get("null_metrics").value, 1.0);
}

TEST(Breakdown, RecallByHand) {
    BreakdownOptions o;
    o.recall = {{1.0, 0.01}, {5.0, 0.1}};
    const Table t = RecallTable(Rows(), o);
    // a: (0.5, 0.005) passes both; (3, 0.02) passes (5, 0.1) only -> 1/4 and 2/4.
    // Column 0 is the pair count (issue 26: breakdown tables show pair counts).
    EXPECT_EQ(t.columns[0].key, "pairs");
    EXPECT_DOUBLE_EQ(t.rows[0].Get(t.columns[0].key).value, 4.0);
    EXPECT_DOUBLE_EQ(t.rows[0].Get(t.columns[1].key).value, 0.25);
    EXPECT_DOUBLE_EQ(t.rows[0].Get(t.columns[2].key).value, 0.5);
    EXPECT_DOUBLE_EQ(t.rows[1].Get(t.columns[2].key).value, 0.0);  // b: mae_t 0.2
}

TEST(Breakdown, PerCategoryMeans) {
    const Table t = CategoryTable(Rows(), BreakdownOptions{});
    EXPECT_DOUBLE_EQ(t.rows[0].Get("chair").value, 1.75);
    EXPECT_DOUBLE_EQ(t.rows[0].Get("plane").value, 10.0);
    EXPECT_FALSE(t.rows[1].Get("plane").HasValue());
}

TEST(Breakdown, BinsByMeasuredOverlap) {
    BreakdownOptions o;
    o.overlap_edges = {0.0, 0.6, 0.8, 1.0001};
    const Table t = OverlapTable(Rows(), o);
    ASSERT_EQ(t.columns.size(), 3u);
    // min(src, src + 0.05) = src: 0.55 -> bin 0, 0.75 x2 -> bin 1, 0.95 -> bin 2.
    EXPECT_DOUBLE_EQ(t.rows[0].Get(t.columns[0].key).value, 0.5);
    EXPECT_DOUBLE_EQ(t.rows[0].Get(t.columns[1].key).value, 5.5);
    EXPECT_EQ(t.rows[0].Get(t.columns[1].key).pairs, 2u);
    // The count is shown in the cell, and the CI (issue 41 item 2): the bin holds 3 and 8, so
    // a resample's mean is 3, 5.5 or 8 with probability 1/4, 1/2, 1/4 and the 2.5% and 97.5%
    // quantiles of 1000 resampled means are 3 and 8: half-width 2.5.
    EXPECT_EQ(t.rows[0].Get(t.columns[1].key).text, "5.5000 ± 2.5000 (n=2)");
    EXPECT_DOUBLE_EQ(t.rows[0].Get(t.columns[2].key).value, 12.0);
    EXPECT_TRUE(t.notes.empty());
}

TEST(Breakdown, RowsWithoutOverlapRatiosAreLeftOutAndCounted) {
    // Rows written before rows recorded overlap ratios read none (not 0, which would fall in
    // the first bin): a's first row leaves bin 0, which then has no pair.
    auto rows = Rows();
    rows[0].source_overlap_ratio.reset();
    rows[0].target_overlap_ratio.reset();
    BreakdownOptions o;
    o.overlap_edges = {0.0, 0.6, 0.8, 1.0001};
    const Table t = OverlapTable(rows, o);
    EXPECT_FALSE(t.rows[0].Get(t.columns[0].key).HasValue());
    EXPECT_DOUBLE_EQ(t.rows[0].Get(t.columns[1].key).value, 5.5);
    ASSERT_EQ(t.notes.size(), 1u);
    EXPECT_EQ(t.notes[0].rfind("1 rows carry no overlap ratios", 0), 0u) << t.notes[0];
}

}  // namespace
}  // namespace regbench
