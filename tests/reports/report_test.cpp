#include "reports/report.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "core/transform.hpp"
#include "tests/testing/expect_throw.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

ResultRow Row(const std::string& method, double mae_r, double mae_t, double seconds,
              Status status = Status::kOk, std::size_t pair = 0) {
    ResultRow r;
    r.pair = pair;
    r.method = method;
    r.status = status;
    r.result.seconds = seconds;
    r.metrics.mae_r = mae_r;
    r.metrics.mae_t = mae_t;
    r.metrics.mse_r = mae_r * mae_r;
    r.metrics.mse_t = mae_t * mae_t;
    r.metrics.rre = mae_r * 2;
    r.metrics.rte = mae_t * 2;
    r.metrics.ccd = 0.05;
    r.metrics.chamfer = 0.01;
    r.data.pairs_file = "a.h5";
    r.data.content_hash = "fnv1a64:aaaa";
    return r;
}

/// Rows of one method on distinct pairs 0, 1, 2, ...
std::vector<ResultRow> Numbered(std::vector<ResultRow> rows) {
    for (std::size_t k = 0; k < rows.size(); ++k) rows[k].pair = k;
    return rows;
}

TEST(Report, AggregatesPerMethodByHand) {
    std::vector<ResultRow> rows =
        Numbered({Row("a", 0.5, 0.01, 1.0), Row("a", 2.0, 0.01, 3.0),
                  Row("a", 0.2, 0.5, 2.0, Status::kFailed), Row("b", 10.0, 0.2, 0.1)});
    const auto s = Summarize(rows, ReportOptions{});
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(s[0].method, "a");
    EXPECT_EQ(s[0].pairs, 3u);
    EXPECT_EQ(s[0].failed, 1u);
    EXPECT_NEAR(s[0].mae_r.mean, 0.9, 1e-12);
    EXPECT_NEAR(s[0].rmse_r.mean, std::sqrt((0.25 + 4.0 + 0.04) / 3.0), 1e-12);
    // recall@(1, 0.1): only the first row (0.5 deg, 0.01).
    EXPECT_NEAR(s[0].recall.mean, 1.0 / 3.0, 1e-12);
    EXPECT_NEAR(s[0].median_seconds, 2.0, 1e-12);
    EXPECT_LE(s[0].mae_r.lo, s[0].mae_r.mean);
    EXPECT_GE(s[0].mae_r.hi, s[0].mae_r.mean);
    EXPECT_NEAR(s[1].recall.mean, 0.0, 1e-12);
    ReportTable rt;
    rt.methods = s;
    const Table t = SummaryTable(rt, ReportOptions{});
    const std::string md = TableToMarkdown(t, TableForm::kFull);
    EXPECT_NE(md.find("| a | 3 | 1 | 0.9000 ± "), std::string::npos) << md;
    EXPECT_NE(md.find("| b |"), std::string::npos);
    // The interval column is data now (mae_r shows its CI itself); CSV and JSON keep it.
    EXPECT_EQ(md.find("mae_r 95% CI"), std::string::npos) << md;
    EXPECT_NE(TablesToCsv({t}).find(",a,mae_r.ci95,mae_r 95% CI,"), std::string::npos);
    // Issue 41 item 2: recall and success carry their Wilson interval. a: 1 of 3 pairs
    // recalled; scipy 1.10.1 binomtest(1, 3).proportion_ci(method="wilson") =
    // (0.06149194472039626, 0.7923403991979523).
    EXPECT_NEAR(s[0].recall.lo, 0.06149194472039626, 1e-12);
    EXPECT_NEAR(s[0].recall.hi, 0.7923403991979523, 1e-12);
    EXPECT_NE(md.find("0.333 [0.061, 0.792]"), std::string::npos) << md;
    // rmse_r's CI is the root of the mean square's: it brackets the root mean square.
    EXPECT_LE(s[0].rmse_r.lo, s[0].rmse_r.mean);
    EXPECT_GE(s[0].rmse_r.hi, s[0].rmse_r.mean);
    EXPECT_LT(s[0].rmse_r.lo, s[0].rmse_r.hi);
    // CSV and JSON carry the data columns Markdown leaves out (chamfer, threads, params).
    EXPECT_NE(TablesToCsv({t}).find(",a,mae_r,mae_r [deg],measured,0.9,"), std::string::npos);
    EXPECT_NE(TablesToCsv({t}).find(",a,params,params,measured,,,,,{}"), std::string::npos)
        << TablesToCsv({t});
}

TEST(Report, SuccessThresholdsAreOptions) {
    // rre = 2 * mae_r, rte = 2 * mae_t: rows (rre 1, rte 0.02) and (rre 4, rte 0.02).
    const std::vector<ResultRow> rows = Numbered({Row("a", 0.5, 0.01, 1), Row("a", 2.0, 0.01, 1)});
    ReportOptions o;
    EXPECT_NEAR(Summarize(rows, o)[0].success.mean, 1.0, 1e-12);  // rre < 5, rte < 0.1
    o.success_rre_deg = 3.0;
    EXPECT_NEAR(Summarize(rows, o)[0].success.mean, 0.5, 1e-12);
    o.success_rte = 0.01;
    EXPECT_NEAR(Summarize(rows, o)[0].success.mean, 0.0, 1e-12);
}

TEST(Report, MedianOfEvenCountAveragesTheMiddle) {
    const auto s = Summarize(Numbered({Row("a", 1, 0, 1.0), Row("a", 1, 0, 4.0),
                                       Row("a", 1, 0, 2.0), Row("a", 1, 0, 3.0)}),
                             ReportOptions{});
    EXPECT_NEAR(s[0].median_seconds, 2.5, 1e-12);
}

TEST(Report, RowWithoutMetricsIsRejectedWhenRead) {
    const auto path = regbench::testing::TempPath("report_nometrics.jsonl");
    std::ofstream(path) << "{\"method\": \"a\", \"pair\": 0}\n";
    try {
        ReadResultRows(path.string());
        FAIL() << "expected an error";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(path.string() + ":1"), std::string::npos) << e.what();
    }
    std::filesystem::remove(path);
}

TEST(Report, DifferentPairFilesGiveSeparateTables) {
    std::vector<ResultRow> rows = Numbered({Row("a", 1, 0, 1), Row("a", 3, 0, 1)});
    rows[1].pair = 0;  // same pair index, but from another pair file
    rows[1].data.pairs_file = "b.h5";
    rows[1].data.content_hash = "fnv1a64:bbbb";
    const auto tables = BuildTables(rows, ReportOptions{});
    ASSERT_EQ(tables.size(), 2u);
    EXPECT_EQ(tables[0].data.pairs_file, "a.h5");
    EXPECT_EQ(tables[1].data.pairs_file, "b.h5");
    EXPECT_NEAR(tables[0].methods[0].mae_r.mean, 1.0, 1e-12);
    EXPECT_NEAR(tables[1].methods[0].mae_r.mean, 3.0, 1e-12);
    const std::string md = TablesToMarkdown(SummaryTables(tables, ReportOptions{}));
    EXPECT_NE(md.find("Table 1 of 2"), std::string::npos) << md;
    EXPECT_NE(md.find("file `b.h5`"), std::string::npos) << md;
}

TEST(Report, SameFileNameButOtherContentIsNotPooled) {
    std::vector<ResultRow> rows = Numbered({Row("a", 1, 0, 1), Row("a", 3, 0, 1)});
    rows[1].data.content_hash = "fnv1a64:cccc";  // regenerated file under the same name
    EXPECT_EQ(BuildTables(rows, ReportOptions{}).size(), 2u);
}

TEST(Report, DifferentConventionsAreNotPooled) {
    std::vector<ResultRow> rows = Numbered({Row("a", 1, 0, 1), Row("a", 3, 0, 1)});
    rows[1].euler = EulerConvention::kXyz;
    const auto tables = BuildTables(rows, ReportOptions{});
    ASSERT_EQ(tables.size(), 2u);
    EXPECT_NE(DescribeTable(tables[0]).find("as_euler('zyx')"), std::string::npos);
    EXPECT_NE(DescribeTable(tables[1]).find("as_euler('xyz')"), std::string::npos);
}

TEST(Report, ParameterSetsOfOneMethodAreSeparateRows) {
    std::vector<ResultRow> rows = {Row("icp", 1, 0, 1, Status::kOk, 0),
                                   Row("icp", 3, 0, 1, Status::kOk, 0)};
    rows[0].params = {{"max_iterations", 10}};
    rows[1].params = {{"max_iterations", 50}};
    const auto tables = BuildTables(rows, ReportOptions{});
    ASSERT_EQ(tables.size(), 1u);
    ASSERT_EQ(tables[0].methods.size(), 2u);
    EXPECT_EQ(tables[0].methods[0].label, "icp {\"max_iterations\":10}");
    EXPECT_NEAR(tables[0].methods[1].mae_r.mean, 3.0, 1e-12);
}

/// `method` on pairs first..last of a.h5 with mae_r = 1 + pair (so a subset's mean is known).
std::vector<ResultRow> OnPairs(const std::string& method, std::size_t first, std::size_t last) {
    std::vector<ResultRow> rows;
    for (std::size_t k = first; k <= last; ++k) {
        rows.push_back(Row(method, 1.0 + static_cast<double>(k), 0.01, 1.0, Status::kOk, k));
    }
    return rows;
}

TEST(Report, MethodsOnDifferentPairsOfOneFileAreRefusedNamingThem) {
    // Issue 26: ogmm on 10 pairs (--shard 0/3) and icp on 30 shared one table silently.
    std::vector<ResultRow> rows = OnPairs("icp", 0, 29);
    for (auto& r : OnPairs("ogmm", 0, 9)) rows.push_back(r);
    testing::ExpectThrowsWith<std::runtime_error>([&] { BuildTables(rows, ReportOptions{}); },
                                                  "different pairs of a.h5", "icp: 30", "ogmm: 10",
                                                  "--common-pairs");
}

// Issue 54 item 1: the caption states the thresholds in the data's units and says when a
// metric saturated for every method (CCD at 2 x clip = 0.2 by its definition, a rate at 0).
TEST(Report, CaptionStatesThresholdsAndSaturatedMetrics) {
    std::vector<ResultRow> rows = Numbered({Row("a", 10.0, 20.0, 1.0), Row("a", 12.0, 30.0, 1.0)});
    for (auto r : Numbered({Row("b", 11.0, 25.0, 1.0), Row("b", 9.0, 40.0, 1.0)})) {
        rows.push_back(r);
    }
    for (auto& r : rows) r.metrics.ccd = 0.2;  // every call at the clip on both sides
    ReportOptions o;
    o.recall_t = 15.0;
    o.success_rte = 15.0;
    const std::string caption = SummaryTable(BuildTables(rows, o)[0], o).caption;
    EXPECT_NE(caption.find("recall mae_r < 1 deg and mae_t < 15; success rre < 5 deg and rte "
                           "< 15; CCD clip 0.1"),
              std::string::npos)
        << caption;
    EXPECT_NE(caption.find("CCD is at its ceiling 2 x clip = 0.2 for every method"),
              std::string::npos)
        << caption;
    // mae_r >= 9 deg everywhere: recall (< 1 deg) and success (rre = 2 mae_r < 5) are 0.
    EXPECT_NE(caption.find("recall and success are 0 for every method"), std::string::npos)
        << caption;
    // One method below the ceiling and recalled once: neither note.
    rows[0].metrics.ccd = 0.05;
    rows[0].metrics.mae_r = 0.5;
    rows[0].metrics.rre = 1.0;
    rows[0].metrics.mae_t = rows[0].metrics.rte = 0.01;
    const std::string mixed = SummaryTable(BuildTables(rows, o)[0], o).caption;
    EXPECT_EQ(mixed.find("Saturated"), std::string::npos) << mixed;
}

// Issue 54 item 1: the distance thresholds not given follow the pair file's scale (rows'
// data.scale, `generate --scale`). Expected by hand: rows in millimetres (scale 150) with mae_t
// 5 and 20 (rte = 2 mae_t = 10 and 40), mae_r 0.5 (rre 1): recall@(1, 0.1 x 150 = 15) accepts
// the first (5 < 15), success rre < 5 and rte < 15 the first (10 < 15); KITTI's rte < 2 m
// becomes rte < 300, which both pass. The same rows at scale 1 pass nothing (mae_t >= 5 > 0.1,
// rte >= 10 > 2); a threshold given on the command line is used as is.
TEST(Report, DistanceThresholdsNotGivenScaleWithThePairFile) {
    std::vector<ResultRow> rows = Numbered({Row("a", 0.5, 5.0, 1.0), Row("a", 0.5, 20.0, 1.0)});
    for (auto& r : rows) r.data.scale = 150.0;
    ReportOptions o;
    const MethodSummary mm = BuildTables(rows, o)[0].methods[0];
    EXPECT_DOUBLE_EQ(mm.recall.mean, 0.5);
    EXPECT_DOUBLE_EQ(mm.success.mean, 0.5);
    const std::string caption = SummaryTable(BuildTables(rows, o)[0], o).caption;
    EXPECT_NE(caption.find("recall mae_r < 1 deg and mae_t < 15; success rre < 5 deg and rte "
                           "< 15"),
              std::string::npos)
        << caption;
    EXPECT_NE(caption.find("The pair file's scale is 150 (`generate --scale`): every distance "
                           "threshold not given on the command line is its unit-sphere default "
                           "times 150."),
              std::string::npos)
        << caption;
    // Applying the scale twice must not scale twice (DescribeConventions and SummaryTable
    // both call ForData).
    EXPECT_NE(caption.find("recall@(1,15)"), std::string::npos) << caption;
    ReportOptions kitti = o;
    kitti.success_rule = "kitti";
    EXPECT_DOUBLE_EQ(BuildTables(rows, kitti)[0].methods[0].success.mean, 1.0);
    const Table k = SummaryTable(BuildTables(rows, kitti)[0], kitti);
    EXPECT_EQ(k.columns[k.ColumnIndex("success")].header, "success kitti(rre<5,rte<300)");
    ReportOptions given = o;
    given.recall_t = 0.1;
    given.recall_t_given = true;
    EXPECT_DOUBLE_EQ(BuildTables(rows, given)[0].methods[0].recall.mean, 0.0);
    EXPECT_DOUBLE_EQ(BuildTables(rows, given)[0].methods[0].success.mean, 0.5);
    const std::string as_given = SummaryTable(BuildTables(rows, given)[0], given).caption;
    EXPECT_NE(as_given.find("mae_t < 0.1; success rre < 5 deg and rte < 15"), std::string::npos)
        << as_given;
    EXPECT_NE(as_given.find("(given as is: --recall-t)"), std::string::npos) << as_given;
    // Unit-sphere rows: the thresholds and the caption as they always were.
    for (auto& r : rows) r.data.scale = 1.0;
    const MethodSummary unit = BuildTables(rows, o)[0].methods[0];
    EXPECT_DOUBLE_EQ(unit.recall.mean, 0.0);
    EXPECT_DOUBLE_EQ(unit.success.mean, 0.0);
    const std::string unit_caption = SummaryTable(BuildTables(rows, o)[0], o).caption;
    EXPECT_EQ(unit_caption.find("scale is"), std::string::npos) << unit_caption;
    EXPECT_NE(unit_caption.find("mae_t < 0.1; success rre < 5 deg and rte < 0.1; CCD clip 0.1"),
              std::string::npos)
        << unit_caption;
}

TEST(Report, CommonPairsRestrictsEveryMethodAndSaysSoInTheCaption) {
    std::vector<ResultRow> rows = OnPairs("icp", 0, 29);
    for (auto& r : OnPairs("ogmm", 0, 9)) rows.push_back(r);
    ReportOptions o;
    o.common_pairs = true;
    const auto tables = BuildTables(rows, o);
    ASSERT_EQ(tables.size(), 1u);
    ASSERT_EQ(tables[0].methods.size(), 2u);
    for (const auto& m : tables[0].methods) {
        EXPECT_EQ(m.pairs, 10u) << m.method;
        // mae_r = 1 + k over k = 0..9: mean 5.5 (by hand), for both methods.
        EXPECT_NEAR(m.mae_r.mean, 5.5, 1e-12) << m.method;
    }
    const std::string caption = DescribeTable(tables[0]);
    EXPECT_NE(caption.find("restricted to the 10 pairs every method has"), std::string::npos)
        << caption;
    EXPECT_NE(caption.find("icp: 30 -> 10"), std::string::npos) << caption;
    EXPECT_NE(TablesToMarkdown(SummaryTables(tables, o)).find("restricted to the 10 pairs"),
              std::string::npos);
    // Methods on the same pairs need no flag and get no note.
    const auto same = BuildTables(OnPairs("icp", 0, 4), ReportOptions{});
    EXPECT_TRUE(same[0].subset.empty());
}

TEST(Report, DuplicateRowIsAnErrorNamingBothLines) {
    std::vector<ResultRow> rows = {Row("a", 1, 0, 1), Row("a", 1, 0, 1)};
    rows[0].origin = "r1.jsonl:4";
    rows[1].origin = "r2.jsonl:7";
    try {
        BuildTables(rows, ReportOptions{});
        FAIL() << "expected an error";
    } catch (const std::runtime_error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("r2.jsonl:7"), std::string::npos) << what;
        EXPECT_NE(what.find("r1.jsonl:4"), std::string::npos) << what;
        EXPECT_NE(what.find("duplicate"), std::string::npos) << what;
    }
}

TEST(Report, NullMetricsCountAsFailedWithTheirLine) {
    std::vector<ResultRow> rows = Numbered({Row("a", 1, 0.01, 1), Row("a", 0.5, 0.01, 1)});
    rows[1].metrics.ccd = std::numeric_limits<double>::quiet_NaN();
    rows[1].origin = "r.jsonl:2";
    const auto tables = BuildTables(rows, ReportOptions{});
    ASSERT_EQ(tables.size(), 1u);
    const MethodSummary& s = tables[0].methods[0];
    EXPECT_EQ(s.pairs, 2u);
    EXPECT_EQ(s.failed, 1u);
    EXPECT_NEAR(s.mae_r.mean, 1.0, 1e-12);  // the null row's numbers are not averaged
    EXPECT_NEAR(s.recall.mean, 0.0, 1e-12);      // 1 deg is not < 1; the null row is not recalled
    ASSERT_EQ(tables[0].notes.size(), 1u);
    EXPECT_NE(tables[0].notes[0].find("r.jsonl:2"), std::string::npos) << tables[0].notes[0];
}

TEST(Report, NullMetricsRoundTripThroughJsonl) {
    ResultRow r = Row("a", 1, 0, 1);
    r.metrics.mae_r = std::numeric_limits<double>::infinity();
    const nlohmann::json j = r;
    EXPECT_TRUE(j["metrics"]["mae_r"].is_null());
    const ResultRow back = j.get<ResultRow>();
    EXPECT_TRUE(std::isnan(back.metrics.mae_r));
}

TEST(Report, BootstrapDoesNotDependOnRowOrderOrTablePosition) {
    std::vector<ResultRow> rows;
    for (std::size_t k = 0; k < 20; ++k) {
        rows.push_back(Row("a", 0.1 * static_cast<double>(k * k % 7), 0, 1, Status::kOk, k));
        rows.push_back(Row("b", 0.3 * static_cast<double>(k % 5), 0, 1, Status::kOk, k));
    }
    const auto first = BuildTables(rows, ReportOptions{})[0].methods;
    std::vector<ResultRow> reversed(rows.rbegin(), rows.rend());  // b now comes first
    const auto second = BuildTables(reversed, ReportOptions{})[0].methods;
    ASSERT_EQ(first.size(), 2u);
    ASSERT_EQ(second.size(), 2u);
    ASSERT_EQ(second[0].method, "b");
    for (const auto& a : first) {
        const auto it = std::find_if(second.begin(), second.end(),
                                     [&](const MethodSummary& b) { return b.method == a.method; });
        ASSERT_NE(it, second.end());
        EXPECT_EQ(a.mae_r.lo, it->mae_r.lo) << a.method;
        EXPECT_EQ(a.mae_r.hi, it->mae_r.hi) << a.method;
        EXPECT_EQ(a.ccd.lo, it->ccd.lo) << a.method;
    }
    EXPECT_LT(first[0].mae_r.lo, first[0].mae_r.hi);  // a real interval, not a constant
}

TEST(Report, CiIsTheOneBootstrapMeanOfThePairValues) {
    // The table's CI is BootstrapMean (reports/statistics.hpp, checked against numpy there) of
    // the method's values in pair order, seed 20230103, stream named by the pair file and the
    // metric: "hash:<content hash>\n<metric>" (docs/metrics.md).
    std::vector<ResultRow> rows;
    std::vector<double> values;
    for (std::size_t k = 0; k < 30; ++k) {
        values.push_back(0.5 + static_cast<double>(k * 7 % 11));
        rows.push_back(Row("a", values.back(), 0, 1, Status::kOk, k));
    }
    std::reverse(rows.begin(), rows.end());  // read in any order: sorted by pair first
    const MethodSummary s = BuildTables(rows, ReportOptions{})[0].methods[0];
    const BootstrapCi expected = BootstrapMean(values, 1000, kDefaultBootstrapSeed,
                                               StreamId("hash:fnv1a64:aaaa\nmae_r"));
    EXPECT_DOUBLE_EQ(s.mae_r.mean, expected.mean);
    EXPECT_EQ(s.mae_r.lo, expected.lo);
    EXPECT_EQ(s.mae_r.hi, expected.hi);
    EXPECT_LT(s.mae_r.lo, s.mae_r.hi);
}

TEST(Report, MethodsOnTheSamePairsDrawTheSameResamples) {
    // Issue 41: icp and open3d-py-icp, equal on every pair, showed 14.6±2.5 and 14.6±2.7 (one
    // bootstrap stream per method). With one stream per (pair file, metric) the resamples are
    // paired: equal values give equal CIs, and a method that is b = a + 1 on every pair has
    // every resampled mean, so both ends, shifted by exactly 1 (hand derivation).
    std::vector<ResultRow> rows;
    for (std::size_t k = 0; k < 25; ++k) {
        const double v = 0.3 + static_cast<double>(k * 5 % 13);
        rows.push_back(Row("a", v, 0.01, 1, Status::kOk, k));
        rows.push_back(Row("b", v, 0.01, 1, Status::kOk, k));
        rows.push_back(Row("c", v + 1.0, 0.01, 1, Status::kOk, k));
    }
    const auto methods = BuildTables(rows, ReportOptions{})[0].methods;
    ASSERT_EQ(methods.size(), 3u);
    EXPECT_EQ(methods[0].mae_r.lo, methods[1].mae_r.lo);
    EXPECT_EQ(methods[0].mae_r.hi, methods[1].mae_r.hi);
    EXPECT_LT(methods[0].mae_r.lo, methods[0].mae_r.hi);
    EXPECT_NEAR(methods[2].mae_r.lo, methods[0].mae_r.lo + 1.0, 1e-12);
    EXPECT_NEAR(methods[2].mae_r.hi, methods[0].mae_r.hi + 1.0, 1e-12);
}

TEST(Report, EulerOptionRecomputesFromStoredGroundTruth) {
    // R_gt = Rx(10) Ry(20) Rz(30), R_est = Rx(16) Ry(20) Rz(25): 'zyx' angles (30, 20, 10) and
    // (25, 20, 16) -> mae_r 11/3 (hand computation). The row says 0 under 'xyz' on purpose.
    ResultRow r = Row("a", 0.0, 0.0, 1);
    r.euler = EulerConvention::kXyz;
    r.gt_transform = MakeTransform(RotationXyzProductDeg(10, 20, 30), Eigen::Vector3d::Zero());
    r.result.T_target_source =
        MakeTransform(RotationXyzProductDeg(16, 20, 25), Eigen::Vector3d::Zero());
    ReportOptions o;
    o.euler = EulerConvention::kZyx;
    const auto tables = BuildTables({r}, o);
    ASSERT_EQ(tables.size(), 1u);
    EXPECT_EQ(tables[0].euler, EulerConvention::kZyx);
    EXPECT_NEAR(tables[0].methods[0].mae_r.mean, 11.0 / 3.0, 1e-9);
    // Without a stored ground truth the report refuses instead of mixing conventions.
    r.gt_transform.reset();
    EXPECT_THROW(BuildTables({r}, o), std::runtime_error);
}

TEST(Report, OldRowsWithoutEulerKeyReadAsXyz) {
    // A row as regbench wrote it before the convention was recorded.
    const auto j = nlohmann::json::parse(
        R"({"pair": 3, "method": "icp", "status": "ok", "seconds": 0.5,
            "metrics": {"mae_r": 1, "mae_t": 0, "mse_r": 1, "mse_t": 0, "rre": 1, "rte": 0,
                        "ccd": 0, "chamfer": 0, "ccd_within_clip": true},
            "data": {"pairs_file": "p.h5", "dataset": "d", "protocol": "x",
                     "pairing": "y", "seed": 1}})");
    const ResultRow r = j.get<ResultRow>();
    EXPECT_EQ(r.euler, EulerConvention::kXyz);
    EXPECT_EQ(r.pair, 3u);
    EXPECT_TRUE(r.data.content_hash.empty());
    EXPECT_TRUE(std::isnan(r.metrics.overlap_rmse));
    // No overlap ratios either: none read (not 0, a ratio), and none written back.
    EXPECT_FALSE(r.source_overlap_ratio.has_value());
    EXPECT_FALSE(r.target_overlap_ratio.has_value());
    EXPECT_FALSE(nlohmann::json(r).contains("source_overlap_ratio"));
}

TEST(Report, UnknownKeysSurviveARoundTrip) {
    ResultRow r = Row("a", 1, 0, 1);
    r.other["measured_overlap"] = 0.42;
    const ResultRow back = nlohmann::json(r).get<ResultRow>();
    EXPECT_EQ(back.other["measured_overlap"], 0.42);
}

TEST(Report, StatusNamesAreTheRowStrings) {
    for (Status s :
         {Status::kOk, Status::kFailed, Status::kTimeout, Status::kCrashed, Status::kMissing}) {
        EXPECT_EQ(ParseStatus(ToString(s)), s);
    }
    EXPECT_STREQ(ToString(Status::kMissing), "missing");
    EXPECT_THROW(ParseStatus("nope"), std::invalid_argument);
}

TEST(Report, Recall3dmatchUsesOverlapRmseRreAndRte) {
    // Thresholds: overlap RMSE < 0.2, rre < 15, rte < 0.3.
    std::vector<ResultRow> rows =
        Numbered({Row("a", 1, 0.01, 1), Row("a", 1, 0.01, 1), Row("a", 10, 0.01, 1)});
    rows[0].metrics.overlap_rmse = 0.1;  // recalled
    rows[1].metrics.overlap_rmse = 0.3;  // RMSE too large
    rows[2].metrics.overlap_rmse = 0.1;  // rre = 20 >= 15
    ReportOptions o;
    o.recall_3dmatch = true;
    EXPECT_NEAR(Summarize(rows, o)[0].recall_3dmatch.mean, 1.0 / 3.0, 1e-12);
}

// Issue 41 item 6: `report` said how many calls failed, never why; and a checkpoint's row was
// labelled by the method alone, whichever model and training step it ran.
TEST(Report, SaysWhyCallsFailedAndWhichCheckpointRan) {
    std::vector<ResultRow> rows =
        Numbered({Row("icp", 1, 0, 1), Row("icp", 2, 0, 1, Status::kFailed),
                  Row("icp", 3, 0, 1, Status::kTimeout)});
    rows[1].result.message = "diverged: 7 correspondences";
    rows[2].result.message = "killed after 5 s";
    for (std::size_t k = 0; k < 3; ++k) {
        ResultRow r = Row("ogmm", 1, 0, 1, Status::kOk, k);
        r.result.extra = {{"checkpoint", "ck/ogmm-small/last"},
                          {"checkpoint_label", "model ogmm-small, step 142"}};
        rows.push_back(r);
    }
    const ReportOptions o;
    const std::string md = TableToMarkdown(SummaryTable(BuildTables(rows, ReportOptions{})[0], o));
    EXPECT_NE(md.find("Why calls failed (first message per method):"), std::string::npos) << md;
    EXPECT_NE(md.find("- icp: 2 of 3 failed; first: pair 1: failed: diverged: 7 correspondences"),
              std::string::npos)
        << md;
    EXPECT_EQ(md.find("killed after"), std::string::npos) << md;  // the first only
    EXPECT_NE(md.find("| ogmm (model ogmm-small, step 142) |"), std::string::npos) << md;
}

// Issue 41 item 3: rows measured with another CCD clip or with Open3D's fitness say so.
TEST(Report, ShowsTheCcdClipAndOpen3dFitnessWhenMeasured) {
    std::vector<ResultRow> rows = Numbered({Row("icp", 1, 0, 1), Row("icp", 2, 0, 1)});
    for (auto& r : rows) {
        r.metrics.ccd_clip = 5.0;
        r.metrics.inlier_threshold = 2.0;
        r.metrics.fitness = r.pair == 0 ? 0.5 : 1.0;
        r.metrics.inlier_rmse = 0.25;
    }
    const std::string md =
        TableToMarkdown(SummaryTable(BuildTables(rows, ReportOptions{})[0], ReportOptions{}));
    EXPECT_NE(md.find("ccd (clip 5)"), std::string::npos) << md;
    EXPECT_NE(md.find("fitness@2"), std::string::npos) << md;
    EXPECT_NE(md.find("0.750"), std::string::npos) << md;  // mean fitness (0.5 + 1) / 2
    rows[1].metrics.ccd_clip = 0.1;                        // one row measured otherwise: refused
    EXPECT_THROW(BuildTables(rows, ReportOptions{}), std::runtime_error);
}

}  // namespace
}  // namespace regbench
