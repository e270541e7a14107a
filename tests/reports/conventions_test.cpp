// Issue 54 items 2-4: the conventions of `report` (success rules, rre/rte over successful
// pairs, rates per scene), its timing table, success curves with their AUC and the difficulty
// breakdowns. Expected values from numpy 1.24 / scipy 1.10.1 (/usr/bin/python3) or by hand,
// as each test says.
#include "reports/conventions.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>
#include <vector>

#include "core/math_constants.hpp"
#include "core/transform.hpp"
#include "reports/breakdown.hpp"
#include "reports/curves.hpp"
#include "reports/report.hpp"
#include "reports/timing.hpp"
#include "tests/testing/expect_throw.hpp"

namespace regbench {
namespace {

struct PairCase {
    double rre, rte, mae_r, mae_t, overlap_rmse;
    const char* shape;
    double seconds, cpu;
    double rotation_deg, translation, overlap;
};

// Eight pairs of method "a": errors, the scene (shape) of each, times, and the ground truth's
// rotation angle (about z), translation length (along x) and source overlap ratio.
const std::vector<PairCase> kPairs = {
    {1.0, 0.05, 0.5, 0.02, 0.10, "s1", 0.1, 0.08, 10, 0.10, 0.90},
    {4.0, 0.50, 2.0, 0.10, 0.15, "s1", 0.3, 0.20, 40, 0.40, 0.60},
    {7.0, 1.50, 3.0, 0.50, 0.30, "s2", 0.2, 0.15, 70, 0.70, 0.40},
    {2.0, 0.08, 0.8, 0.05, 0.05, "s2", 0.5, 0.40, 20, 0.20, 0.80},
    {20.0, 3.0, 10.0, 1.0, 0.90, "s2", 0.4, 0.30, 100, 1.00, 0.30},
    {3.0, 0.25, 1.5, 0.09, 0.19, "s3", 0.6, 0.50, 50, 0.50, 0.65},
    {14.0, 0.2, 6.0, 0.10, 0.25, "s3", 0.7, 0.55, 35, 0.35, 0.75},
    {0.5, 0.01, 0.2, 0.005, 0.01, "s3", 2.0, 1.90, 5, 0.65, 0.95},
};

std::vector<ResultRow> Rows() {
    std::vector<ResultRow> rows;
    for (std::size_t k = 0; k < kPairs.size(); ++k) {
        const PairCase& c = kPairs[k];
        ResultRow r;
        r.pair = k;
        r.method = "a";
        r.shape = c.shape;
        r.category = "cat";
        r.metrics.rre = c.rre;
        r.metrics.rte = c.rte;
        r.metrics.mae_r = c.mae_r;
        r.metrics.mae_t = c.mae_t;
        r.metrics.mse_r = c.mae_r * c.mae_r;
        r.metrics.mse_t = c.mae_t * c.mae_t;
        r.metrics.ccd = 0.05;
        r.metrics.chamfer = 0.01;
        r.metrics.overlap_rmse = c.overlap_rmse;
        r.result.seconds = c.seconds;
        r.result.cpu_seconds = c.cpu;
        const Eigen::Matrix3d R =
            Eigen::AngleAxisd(c.rotation_deg * kDegToRad, Eigen::Vector3d::UnitZ()).matrix();
        r.gt_transform = MakeTransform(R, Eigen::Vector3d(c.translation, 0, 0));
        r.source_overlap_ratio = c.overlap;
        r.target_overlap_ratio = c.overlap + 0.02;
        r.data.pairs_file = "p.h5";
        r.machine = {{"cpu", "Test CPU"},
                     {"libraries",
                      {{"eigen", "3.4.0"}, {"open3d", "0.16.1"}, {"libtorch", "1.13.0"},
                       {"blas", "TestBLAS"}}}};
        rows.push_back(r);
    }
    return rows;
}

MethodSummary One(const ReportOptions& o) {
    const auto s = Summarize(Rows(), o);
    EXPECT_EQ(s.size(), 1u);
    return s.front();
}

TEST(Conventions, SuccessPresetsByHand) {
    // By hand over kPairs: kitti (rre<5, rte<2) passes pairs 0, 1, 3, 5, 7; 3dmatch-rre-rte
    // (rre<15, rte<0.3) 0, 3, 5, 6, 7; 3dmatch-rmse (overlap_rmse<0.2) 0, 1, 3, 5, 7;
    // paper-recall (mae_r<1, mae_t<0.1) 0, 3, 7; rre-rte at the defaults (rre<5, rte<0.1)
    // 0, 3, 7.
    const std::vector<std::pair<std::string, double>> cases = {
        {"kitti", 5.0 / 8}, {"3dmatch-rre-rte", 5.0 / 8}, {"3dmatch-rmse", 5.0 / 8},
        {"paper-recall", 3.0 / 8}, {"rre-rte", 3.0 / 8}};
    for (const auto& [name, rate] : cases) {
        ReportOptions o;
        o.success_rule = name;
        EXPECT_DOUBLE_EQ(One(o).success.mean, rate) << name;
    }
    // The per-pair rate keeps its Wilson interval: scipy.stats.binomtest(5, 8)
    // .proportion_ci(method="wilson").
    ReportOptions o;
    o.success_rule = "kitti";
    const MethodSummary s = One(o);
    EXPECT_NEAR(s.success.lo, 0.3057423946026273, 1e-12);
    EXPECT_NEAR(s.success.hi, 0.8631557141764027, 1e-12);
    EXPECT_THROW(FindSuccessRule("kiti", 5, 0.1), std::invalid_argument);
}

TEST(Conventions, DefaultHeadersAreThoseBeforeRulesHadNames) {
    ReportOptions o;
    const std::vector<ReportTable> tables = BuildTables(Rows(), o);
    const Table t = SummaryTable(tables.front(), o);
    EXPECT_EQ(t.columns[t.ColumnIndex("success")].header, "success(rre<5,rte<0.1)");
    EXPECT_EQ(t.columns[t.ColumnIndex("rre")].header, "rre [deg]");
    // The caption's first line is unchanged; the conventions are a line of their own.
    EXPECT_EQ(t.caption.find("Data: "), 0u);
    const std::string line = t.caption.substr(t.caption.find('\n') + 1);
    EXPECT_EQ(line.find("Conventions: rre/rte averaged over all pairs"), 0u) << line;
    EXPECT_NE(line.find("rates over pairs"), std::string::npos) << line;
    EXPECT_NE(line.find("success rule rre-rte: rre<5,rte<0.1"), std::string::npos) << line;
    o.success_rule = "kitti";
    o.rre_rte_over = ErrorPairs::kSuccessful;
    o.rates_per = RatePer::kScene;
    const Table k = SummaryTable(BuildTables(Rows(), o).front(), o);
    EXPECT_EQ(k.columns[k.ColumnIndex("success")].header, "success kitti(rre<5,rte<2)");
    EXPECT_EQ(k.columns[k.ColumnIndex("rre")].header, "rre [deg] (successful)");
    EXPECT_NE(k.caption.find("rates averaged over 3 scenes"), std::string::npos) << k.caption;
    EXPECT_NE(k.caption.find("--rre-rte-over successful"), std::string::npos) << k.caption;
}

TEST(Conventions, RreRteOverSuccessfulPairsByHand) {
    ReportOptions o;
    o.success_rule = "kitti";
    o.rre_rte_over = ErrorPairs::kSuccessful;
    const MethodSummary s = One(o);
    // Pairs 0, 1, 3, 5, 7: rre (1 + 4 + 2 + 3 + 0.5) / 5, rte (0.05 + 0.5 + 0.08 + 0.25 +
    // 0.01) / 5; the other means stay over all 8 pairs.
    EXPECT_EQ(s.successful, 5u);
    EXPECT_NEAR(s.rre.mean, 2.1, 1e-12);
    EXPECT_NEAR(s.rte.mean, 0.178, 1e-12);
    EXPECT_NEAR(s.mae_r.mean, 24.0 / 8, 1e-12);  // 0.5+2+3+0.8+10+1.5+6+0.2 = 24
    o.rre_rte_over = ErrorPairs::kAll;
    EXPECT_NEAR(One(o).rre.mean, 51.5 / 8, 1e-12);  // 1+4+7+2+20+3+14+0.5 = 51.5
}

TEST(Conventions, RatesPerSceneAverageTheScenesRates) {
    ReportOptions o;
    o.success_rule = "kitti";
    o.rates_per = RatePer::kScene;
    const MethodSummary s = One(o);
    // By hand: s1 passes 2 of 2, s2 1 of 3 (pair 3), s3 2 of 3 (5, 7): (1 + 1/3 + 2/3) / 3.
    EXPECT_NEAR(s.success.mean, 2.0 / 3, 1e-12);
    EXPECT_EQ(s.rate_groups, 3u);
    EXPECT_LE(s.success.lo, s.success.mean);
    EXPECT_GE(s.success.hi, s.success.mean);
    // One category: the per-category rate is the per-pair fraction, 5 / 8.
    o.rates_per = RatePer::kCategory;
    EXPECT_NEAR(One(o).success.mean, 5.0 / 8, 1e-12);
    // A pair file without scene ids: refused, naming the fix.
    auto rows = Rows();
    rows[3].shape.clear();
    o.rates_per = RatePer::kScene;
    testing::ExpectThrowsWith([&] { Summarize(rows, o); }, "--rates-per pair");
}

TEST(Conventions, RmseRuleRefusesRowsWithoutOverlapRmse) {
    auto rows = Rows();
    rows[2].metrics.overlap_rmse = std::nan("");
    ReportOptions o;
    o.success_rule = "3dmatch-rmse";
    testing::ExpectThrowsWith([&] { Summarize(rows, o); }, "overlap_rmse");
}

TEST(Timing, MedianAndP95OfWallAndCpuLikeNumpy) {
    const MethodSummary s = One(ReportOptions{});
    // np.median / np.quantile(v, 0.95) (linear) of the seconds and cpu columns of kPairs.
    EXPECT_NEAR(s.median_seconds, 0.45, 1e-12);
    EXPECT_NEAR(s.p95_seconds, 1.5449999999999993, 1e-12);
    EXPECT_NEAR(s.median_cpu_seconds, 0.35, 1e-12);
    EXPECT_NEAR(s.p95_cpu_seconds, 1.4274999999999993, 1e-12);
    const std::vector<ReportTable> tables = BuildTables(Rows(), ReportOptions{});
    const Table t = TimingTable(tables.front());
    EXPECT_NEAR(t.rows[0].Get("p95_cpu_seconds").value, 1.4274999999999993, 1e-12);
    for (const char* part : {"threads per call 1", "CPU Test CPU", "LibTorch 1.13.0",
                             "Open3D 0.16.1", "Eigen 3.4.0", "LibTorch's BLAS TestBLAS"}) {
        EXPECT_NE(t.caption.find(part), std::string::npos) << part << ": " << t.caption;
    }
}

TEST(Timing, RowsWithoutCpuTimeOrMachineSaySo) {
    auto rows = Rows();
    for (auto& r : rows) {
        r.result.cpu_seconds = 0.0;  // as rows from before cpu_seconds read
        r.machine = nlohmann::json::object();
    }
    const MethodSummary s = Summarize(rows, ReportOptions{}).front();
    EXPECT_TRUE(std::isnan(s.median_cpu_seconds));
    EXPECT_TRUE(std::isnan(s.p95_cpu_seconds));
    std::vector<const ResultRow*> ptrs;
    for (const auto& r : rows) ptrs.push_back(&r);
    const std::string env = DescribeEnvironment(ptrs);
    EXPECT_NE(env.find("CPU not recorded"), std::string::npos) << env;
    EXPECT_NE(env.find("8 of 8 rows record no CPU model"), std::string::npos) << env;
}

TEST(SuccessCurve, RatesAndAucAgainstATrapezoid) {
    const Table t = SuccessCurveTable(Rows(), {"rre", 15.0}, 5);
    ASSERT_EQ(t.rows.size(), 1u);
    // rre = 1, 4, 7, 2, 20, 3, 14, 0.5: below 3 -> 3 of 8, below 6 -> 5 of 8 (by hand).
    EXPECT_DOUBLE_EQ(t.rows[0].Get("below:3").value, 3.0 / 8);
    EXPECT_DOUBLE_EQ(t.rows[0].Get("below:6").value, 5.0 / 8);
    EXPECT_DOUBLE_EQ(t.rows[0].Get("below:15").value, 7.0 / 8);
    // np.trapz of the step curve (np.searchsorted(sorted, x, 'left') / 8) on 3000001 points
    // of [0, 15], over 15: 0.6124999791666705; exactly (by hand) mean(max(0, 1 - e / 15)) =
    // (14 + 11 + 8 + 13 + 0 + 12 + 1 + 14.5) / 120 = 0.6125.
    EXPECT_NEAR(t.rows[0].Get("auc").value, 0.6124999791666705, 1e-6);
    EXPECT_DOUBLE_EQ(t.rows[0].Get("auc").value, 0.6125);
    // rte on [0, 0.3]: the same trapezoid gives 0.37916656249999986.
    const Table r = SuccessCurveTable(Rows(), {"rte", 0.3}, 5);
    EXPECT_NEAR(r.rows[0].Get("auc").value, 0.37916656249999986, 1e-6);
    // A null error is a miss; no errors: NaN.
    EXPECT_DOUBLE_EQ(SuccessAuc({0.0, std::nan("")}, 1.0), 0.5);
    EXPECT_DOUBLE_EQ(SuccessRateBelow({0.0, std::nan("")}, 1.0), 0.5);
    EXPECT_TRUE(std::isnan(SuccessAuc({}, 1.0)));
}

TEST(Difficulty, BinsByRotationTranslationAndOverlapByHand) {
    const BreakdownOptions o;  // edges 0/30/60/180 deg, 0/0.3/0.6/inf, overlap 0/0.5/0.7/1
    const Table rot = DifficultyTable(Rows(), o, Difficulty::kRotation);
    // mae_r by rotation 10, 40, 70, 20, 100, 50, 35, 5 degrees: easy {0, 3, 7}: (0.5 + 0.8 +
    // 0.2) / 3; medium {1, 5, 6}: (2 + 1.5 + 6) / 3; hard {2, 4}: (3 + 10) / 2.
    ASSERT_EQ(rot.columns.size(), 3u);
    EXPECT_EQ(rot.columns[0].header, "easy [0, 30)");
    EXPECT_EQ(rot.columns[2].header, "hard [60, 180]");
    EXPECT_NEAR(rot.rows[0].Get(rot.columns[0].key).value, 0.5, 1e-12);
    EXPECT_NEAR(rot.rows[0].Get(rot.columns[1].key).value, 9.5 / 3, 1e-12);
    EXPECT_NEAR(rot.rows[0].Get(rot.columns[2].key).value, 6.5, 1e-12);
    EXPECT_EQ(rot.rows[0].Get(rot.columns[2].key).pairs, 2u);
    // Translation 0.1, 0.4, 0.7, 0.2, 1.0, 0.5, 0.35, 0.65: easy {0, 3}, medium {1, 5, 6},
    // hard {2, 4, 7}.
    const Table tr = DifficultyTable(Rows(), o, Difficulty::kTranslation);
    EXPECT_EQ(tr.columns[2].header, "hard [0.6, inf)");
    EXPECT_NEAR(tr.rows[0].Get(tr.columns[0].key).value, 0.65, 1e-12);
    EXPECT_NEAR(tr.rows[0].Get(tr.columns[2].key).value, 13.2 / 3, 1e-12);
    EXPECT_EQ(tr.rows[0].Get(tr.columns[2].key).pairs, 3u);
    // Overlap (min of source and source + 0.02) 0.9, 0.6, 0.4, 0.8, 0.3, 0.65, 0.75, 0.95,
    // shown easy first: easy [0.7, 1] {0, 3, 6, 7}, medium {1, 5}, hard {2, 4}.
    const Table ov = DifficultyTable(Rows(), o, Difficulty::kOverlap);
    EXPECT_EQ(ov.columns[0].header, "easy [0.7, 1]");
    EXPECT_EQ(ov.columns[2].header, "hard [0, 0.5)");
    EXPECT_NEAR(ov.rows[0].Get(ov.columns[0].key).value, 7.5 / 4, 1e-12);
    EXPECT_NEAR(ov.rows[0].Get(ov.columns[1].key).value, 1.75, 1e-12);
    EXPECT_NEAR(ov.rows[0].Get(ov.columns[2].key).value, 6.5, 1e-12);
    // Rows without ground truth are left out and counted.
    auto rows = Rows();
    rows[0].gt_transform.reset();
    const Table old = DifficultyTable(rows, o, Difficulty::kRotation);
    ASSERT_EQ(old.notes.size(), 1u);
    EXPECT_NE(old.notes[0].find("1 rows carry no ground truth"), std::string::npos);
    EXPECT_NEAR(old.rows[0].Get(old.columns[0].key).value, 0.5, 1e-12);  // (0.8 + 0.2) / 2
}

// Issue 54 item 1: the paper tables' caption states the CCD clip the rows used in the data's
// units, the pair file's scale when it is not 1, and that CCD saturated when every method's mean
// is at 2 x clip (CCD's ceiling by its definition: two one-sided means, each clipped).
TEST(Conventions, PaperTableCaptionStatesTheClipAndTheScale) {
    std::vector<ResultRow> rows(2);
    for (std::size_t k = 0; k < rows.size(); ++k) {
        rows[k].method = k == 0 ? "icp" : "ogmm";
        rows[k].metrics.ccd_clip = 15.0;
        rows[k].metrics.ccd = 30.0;
        rows[k].data.scale = 150.0;
    }
    const std::vector<const ResultRow*> ptrs = {&rows[0], &rows[1]};
    const std::string mm = PaperTableConventions(ptrs);
    EXPECT_NE(mm.find("Thresholds in the data's length unit: CCD clip 15; pair file scale 150 "
                      "(`generate --scale`)"),
              std::string::npos)
        << mm;
    EXPECT_NE(mm.find("Saturated: CCD is at its ceiling 2 x clip"), std::string::npos) << mm;
    for (auto& r : rows) {
        r.metrics.ccd_clip = kCcdClip;
        r.metrics.ccd = 0.2;
        r.data.scale = 1.0;
    }
    rows[0].metrics.ccd = 0.05;  // one method below the ceiling 0.2: nothing saturated
    const std::string unit = PaperTableConventions(ptrs);
    EXPECT_NE(unit.find("CCD clip 0.1 (the paper's, for unit-sphere objects)."),
              std::string::npos)
        << unit;
    EXPECT_EQ(unit.find("scale"), std::string::npos) << unit;
    EXPECT_EQ(unit.find("Saturated"), std::string::npos) << unit;
}

}  // namespace
}  // namespace regbench
