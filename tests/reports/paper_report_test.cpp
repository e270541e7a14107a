#include "reports/paper_report.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "reports/breakdown.hpp"
#include "reports/paper_tables.hpp"

namespace regbench {
namespace {

/// The OGMM paper's row names of the methods used here (the paper's Tab. 1 and Tab. 6, as
/// data/paper/ogmm_wacv2023_tables.json spells them); the registry's own labels are checked
/// against that file in tests/baselines (PaperLabels.*).
const PaperRows kPaperRows = {{"icp", "ICP"},         {"cpd", "CPD"},   {"fgr", "FGR"},
                              {"deepgmr", "DeepGMR"}, {"ogmm", "OGMM"}, {"gmmreg", "GMMReg"},
                              {"svr", "SVR"},         {"filterreg", "FilterReg"}};

PaperTableOptions Options() {
    PaperTableOptions o;
    o.paper_rows = kPaperRows;
    return o;
}

ResultRow Row(int pair, const std::string& method, double mae_r, double seconds = 0.1) {
    ResultRow r;
    r.pair = static_cast<std::size_t>(pair);
    r.method = method;
    r.result.seconds = seconds;
    r.metrics.mae_r = mae_r;
    r.metrics.mae_t = mae_r / 100;
    r.metrics.ccd = 0.05 + mae_r / 1000;
    return r;
}

Provenance Prov(const std::string& file) {
    Provenance p;
    p.pairs_file = file;
    p.pairs_hash = "abc123";
    p.dataset = "cgal";
    p.split = "test";
    p.protocol = "partial";
    p.pairing = "independent";
    p.seed = 1;
    p.points = 1024;
    p.keep = 0.7;
    p.version = "0.1.0";
    p.fallback = "embedded corpus instead of ModelNet40";
    p.gt_ccd_floor = 0.1041;
    return p;
}

/// Tab. 1 from two small synthetic result sets: cpd and icp on "same", cpd on "cross".
Table Tab1() {
    ResultSet same{"same_category",
                   {Row(0, "cpd", 1.0), Row(1, "cpd", 2.0), Row(2, "cpd", 6.0), Row(0, "icp", 4.0),
                    Row(1, "icp", 5.0), Row(2, "icp", 9.0), Row(0, "gicp", 3.0)},
                   Prov("same.h5"),
                   ""};
    ResultSet cross{
        "cross_category", {Row(0, "cpd", 10.0), Row(1, "cpd", 20.0)}, Prov("cross.h5"), ""};
    PaperTableOptions o = Options();
    o.unavailable = {{"ogmm", "not trained"}};
    return BuildPaperTable(FindPaperTableSpec("table1_modelnet_partial"), {same, cross},
                           LoadPaperTables(DefaultPaperTablesPath()), o);
}

const TableRow& RowNamed(const Table& t, const std::string& label) {
    for (const auto& r : t.rows) {
        if (r.label == label) return r;
    }
    throw std::runtime_error("no row " + label);
}

std::size_t Col(const Table& t, const std::string& key) {
    for (std::size_t i = 0; i < t.columns.size(); ++i) {
        if (t.columns[i].key == key) return i;
    }
    throw std::runtime_error("no column " + key);
}

TEST(PaperReport, Tab1MeansArePlainAveragesAndPaperCellsAreTheJsonNumbers) {
    const Table t = Tab1();
    // Rows in the paper's order (ICP first, OGMM last), then measured-only methods.
    ASSERT_GE(t.rows.size(), 13u);
    EXPECT_EQ(t.rows.front().label, "ICP");
    EXPECT_EQ(t.rows[11].label, "OGMM");
    EXPECT_EQ(t.rows[12].label, "gicp");
    // Hand: cpd same mae_r (1 + 2 + 6) / 3 = 3; cross (10 + 20) / 2 = 15; icp same 6.
    const TableRow& cpd = RowNamed(t, "CPD");
    EXPECT_DOUBLE_EQ(cpd.Get("same_category.mae_r").value, 3.0);
    EXPECT_EQ(cpd.Get("same_category.mae_r").pairs, 3u);
    EXPECT_DOUBLE_EQ(cpd.Get("cross_category.mae_r").value, 15.0);
    EXPECT_NEAR(cpd.Get("same_category.mae_t").value, 0.03, 1e-15);
    EXPECT_DOUBLE_EQ(RowNamed(t, "ICP").Get("same_category.mae_r").value, 6.0);
    // Paper cells, transcribed in data/paper/ogmm_wacv2023_tables.json: CPD same 11.033 /
    // 0.1139 / 0.1110, cross 12.681; ICP same 10.333; RGM (not implemented) 0.8211.
    EXPECT_DOUBLE_EQ(cpd.Get("paper:same_category.mae_r").value, 11.033);
    EXPECT_DOUBLE_EQ(cpd.Get("paper:same_category.mae_t").value, 0.1139);
    EXPECT_DOUBLE_EQ(cpd.Get("paper:same_category.ccd").value, 0.1110);
    EXPECT_DOUBLE_EQ(cpd.Get("paper:cross_category.mae_r").value, 12.681);
    const TableRow& rgm = RowNamed(t, "RGM");
    EXPECT_DOUBLE_EQ(rgm.Get("paper:same_category.mae_r").value, 0.8211);
    EXPECT_FALSE(rgm.Get("same_category.mae_r").HasValue());
    EXPECT_EQ(RowNamed(t, "OGMM").Get("same_category.mae_r").text, "not trained");
    EXPECT_FALSE(RowNamed(t, "gicp").Get("paper:same_category.mae_r").HasValue());
    // Caption names both sides' data and the pairing; notes carry the CCD floor.
    EXPECT_NE(t.caption.find("dataset `cgal`"), std::string::npos) << t.caption;
    EXPECT_NE(t.caption.find("pairing independent"), std::string::npos);
    EXPECT_NE(t.caption.find("ModelNet40 as published"), std::string::npos);
    EXPECT_NE(t.caption.find("embedded corpus instead of ModelNet40"), std::string::npos);
    // Both fixtures' files have the floor 0.1041: one note names both groups.
    ASSERT_EQ(t.notes.size(), 1u);
    EXPECT_NE(t.notes[0].find("Ground-truth CCD floor (same_category, cross_category): 0.1041"),
              std::string::npos)
        << t.notes[0];
}

TEST(PaperReport, CiIsTheBreakdownsCiForTheSameRows) {
    // Issue 26: one HTML report showed Tab. 1 ICP "15.4925 ± 9.7854" and its breakdown
    // "± 10.6347" (two bootstrap streams for one mean). Both now resample with the stream of
    // the metric, 1000 resamples, seed 20230103: the independent computation is the
    // breakdown's DistributionTable over the same rows.
    const std::vector<ResultRow> rows = {Row(0, "icp", 4.0), Row(1, "icp", 5.0), Row(2, "icp", 9.0),
                                         Row(3, "icp", 30.0), Row(4, "icp", 1.5)};
    PaperTableOptions o = Options();
    const Table paper = BuildPaperTable(FindPaperTableSpec("table1_modelnet_partial"),
                                        {ResultSet{"same_category", rows, Prov("same.h5"), ""}},
                                        LoadPaperTables(DefaultPaperTablesPath()), o);
    BreakdownOptions b;
    b.metrics = {"mae_r"};
    const Table dist = DistributionTable(rows, b);
    ASSERT_EQ(dist.rows.size(), 1u);
    const Cell& ours = RowNamed(paper, "ICP").Get("same_category.mae_r");
    const Cell& breakdown = dist.rows[0].Get("mae_r.mean");
    EXPECT_DOUBLE_EQ(ours.value, breakdown.value);
    EXPECT_GT(ours.HalfWidth(), 0.0);
    EXPECT_DOUBLE_EQ(ours.HalfWidth(), breakdown.HalfWidth());
}

TEST(PaperReport, MethodsOnTheSamePairsGetPairedCis) {
    // Issue 41: equal per-pair values gave two different CIs (one stream per method). The
    // stream is now the metric's alone, so ICP and CPD here, equal on every pair, show one CI,
    // and the breakdown of the same rows agrees.
    std::vector<ResultRow> rows;
    for (int k = 0; k < 12; ++k) {
        const double v = 1.0 + (k * 7) % 9;
        rows.push_back(Row(k, "icp", v));
        rows.push_back(Row(k, "cpd", v));
    }
    const Table paper = BuildPaperTable(FindPaperTableSpec("table1_modelnet_partial"),
                                        {ResultSet{"same_category", rows, Prov("same.h5"), ""}},
                                        LoadPaperTables(DefaultPaperTablesPath()),
                                        Options());
    const Cell& icp = RowNamed(paper, "ICP").Get("same_category.mae_r");
    const Cell& cpd = RowNamed(paper, "CPD").Get("same_category.mae_r");
    EXPECT_GT(icp.HalfWidth(), 0.0);
    EXPECT_EQ(icp.ci_lo, cpd.ci_lo);
    EXPECT_EQ(icp.ci_hi, cpd.ci_hi);
    BreakdownOptions b;
    b.metrics = {"mae_r"};
    const Table dist = DistributionTable(rows, b);
    ASSERT_EQ(dist.rows.size(), 2u);
    EXPECT_EQ(dist.rows[0].Get("mae_r.mean").ci_lo, dist.rows[1].Get("mae_r.mean").ci_lo);
    EXPECT_EQ(dist.rows[0].Get("mae_r.mean").ci_hi, icp.ci_hi);
}

TEST(PaperReport, CompactMarkdownFitsOneHundredTwentyColumns) {
    // Issue 41 item 4: Tab. 1's compact table was 193 columns wide ("MAE(R) same_category
    // (paper)" six times). Too wide for 120 columns, it is shown one column group at a time,
    // the group named above its grid and not in every header; the full table stays one grid.
    const Table t = Tab1();
    const std::string md = TableToMarkdown(t);
    std::istringstream in(md);
    for (std::string line; std::getline(in, line);) {
        if (line.rfind("|", 0) == 0) {
            EXPECT_LE(line.size(), 120u) << line;
        }
    }
    const std::size_t same = md.find("*same_category*\n\n| method | MAE(R) (paper) | MAE(t) (paper) |");
    const std::size_t cross = md.find("*cross_category*\n\n| method | MAE(R) (paper) |");
    ASSERT_NE(same, std::string::npos) << md;
    ASSERT_NE(cross, std::string::npos) << md;
    EXPECT_LT(same, cross);
    // The paper's Tab. 1 CPD same_category MAE(R) 11.033 beside ours (mean 3 of 1, 2, 6), and
    // cross_category 12.681 beside ours (mean 15 of 10, 20) in the second grid; CPD is the
    // best measured cell of both MAE(R) columns, so bold.
    const std::size_t cpd_same = md.find("| CPD | **3.0±", same);
    ASSERT_LT(cpd_same, cross) << md;
    EXPECT_EQ(md.find("(11.033)** |", cpd_same), md.find("(11.033)", same) + 0) << md;
    const std::size_t cpd_cross = md.find("| CPD | **15.0±", cross);
    ASSERT_NE(cpd_cross, std::string::npos) << md;
    EXPECT_NE(md.find("(12.681)** |", cpd_cross), std::string::npos) << md;
    const std::string full = TableToMarkdown(t, TableForm::kFull);
    EXPECT_EQ(full.find("*same_category*"), std::string::npos);
    EXPECT_NE(full.find("MAE(R) same_category"), std::string::npos);
}

TEST(PaperReport, SweepTableReadsTransposedPaperCells) {
    // supp_overlap_ratio lists metrics as rows: OGMM 30% mae_r 5.6462, 70% ccd 0.0645.
    const auto paper = LoadPaperTables(DefaultPaperTablesPath());
    EXPECT_DOUBLE_EQ(PaperCell(paper, "supp_overlap_ratio", "OGMM", "30%", "mae_r"), 5.6462);
    EXPECT_DOUBLE_EQ(PaperCell(paper, "supp_overlap_ratio", "OGMM", "70%", "ccd"), 0.0645);
    EXPECT_TRUE(std::isnan(PaperCell(paper, "supp_overlap_ratio", "CPD", "30%", "mae_r")));
    // Ablation tables: rows are variants, no groups.
    EXPECT_DOUBLE_EQ(PaperCell(paper, "table4_ablation_components", "no_OSP", "", "mae_r"), 6.7087);
}

TEST(PaperReport, LatexIsBalancedBooktabsWithTheBestCellBold) {
    const std::string tex = TableToLatex(Tab1());
    const auto count = [&](const std::string& s) {
        std::size_t n = 0;
        for (auto p = tex.find(s); p != std::string::npos; p = tex.find(s, p + 1)) ++n;
        return n;
    };
    EXPECT_EQ(count("\\begin{tabular}"), 1u);
    EXPECT_EQ(count("\\end{tabular}"), 1u);
    EXPECT_EQ(count("\\toprule"), 1u);
    EXPECT_EQ(count("\\midrule"), 1u);
    EXPECT_EQ(count("\\bottomrule"), 1u);
    std::size_t open = 0, close = 0;
    for (char c : tex) {
        open += c == '{';
        close += c == '}';
    }
    EXPECT_EQ(open, close);
    // Every body line has one cell per column: label + 12 columns = 12 '&'.
    const std::size_t body = tex.find("\\midrule\n") + 9;
    const std::string first = tex.substr(body, tex.find('\n', body) - body);
    EXPECT_EQ(std::count(first.begin(), first.end(), '&'), 12) << first;
    // Best (lowest) measured same-category MAE(R) is CPD's 3.0000 with its CI.
    EXPECT_NE(tex.find("\\textbf{3.0000 $\\pm$"), std::string::npos) << tex;
    EXPECT_NE(tex.find("not trained"), std::string::npos);
    EXPECT_NE(tex.find("\\caption{"), std::string::npos);
}

TEST(PaperReport, CsvAndJsonRoundTripWithProvenance) {
    const Table t = Tab1();
    const nlohmann::json j = TablesToJson({t});
    ASSERT_EQ(j.size(), t.rows.size() * t.columns.size());
    const auto records = ParseCsv(TablesToCsv({t}));
    ASSERT_EQ(records.size(), j.size() + 1);
    const auto& header = records.front();
    const auto field = [&](const std::vector<std::string>& rec, const std::string& name) {
        const auto it = std::find(header.begin(), header.end(), name);
        return rec.at(static_cast<std::size_t>(it - header.begin()));
    };
    bool checked = false;
    for (std::size_t i = 1; i < records.size(); ++i) {
        const auto& rec = records[i];
        const auto& js = j[i - 1];
        EXPECT_EQ(field(rec, "row"), js["row"].get<std::string>());
        EXPECT_EQ(field(rec, "column"), js["column"].get<std::string>());
        if (js["value"].is_number()) {
            EXPECT_DOUBLE_EQ(std::stod(field(rec, "value")), js["value"].get<double>());
        }
        if (js["row"] == "CPD" && js["column"] == "cross_category.mae_r") {
            checked = true;
            EXPECT_EQ(field(rec, "pairs_file"), "cross.h5");
            EXPECT_EQ(js["pairs_hash"], "abc123");
            EXPECT_EQ(js["dataset"], "cgal");
            EXPECT_EQ(js["split"], "test");
            EXPECT_EQ(js["protocol"], "partial");
            EXPECT_EQ(js["pairing"], "independent");
            EXPECT_EQ(js["seed"], 1);
            EXPECT_EQ(js["points"], 1024);
            EXPECT_DOUBLE_EQ(js["keep"].get<double>(), 0.7);
            EXPECT_EQ(js["regbench_version"], "0.1.0");
            EXPECT_EQ(field(rec, "source"), "measured");
            EXPECT_DOUBLE_EQ(std::stod(field(rec, "value")), 15.0);
        }
        if (js["row"] == "CPD" && js["column"] == "paper:cross_category.mae_r") {
            EXPECT_EQ(js["source"], "paper");
            EXPECT_EQ(js["pairs_file"], "");
        }
    }
    EXPECT_TRUE(checked);
}

/// A result row of `method` with the CPU time of its call and, for a learned method
/// (`network` > 0), the network's CPU time, MACs and floor as the learned methods write them.
ResultRow TimedRow(int pair, const std::string& method, double cpu_seconds, double network = 0.0,
                   double macs = 0.0, double floor = 0.0) {
    ResultRow r = Row(pair, method, 1.0, 2 * cpu_seconds);  // wall: not what is shown
    r.result.cpu_seconds = cpu_seconds;
    // The calls' clouds: 1024 points sampled (Prov), 70% kept by the crop.
    r.source_points = r.target_points = 717;
    if (network > 0.0) {
        r.result.extra = {{"network_cpu_seconds", network},
                          {"macs", macs},
                          {"floor_seconds", floor},
                          {"gemm_gmac_per_s", 1e-9 * macs / floor},
                          {"blas", "TestBLAS 1.0 (pthreads)"}};
    }
    return r;
}

TEST(PaperReport, TimingTableMeanAndMedianByHand) {
    // Pair 3's row was written before rows had cpu_seconds (it reads 0): no CPU time to show.
    ResultSet s{"",
                {TimedRow(0, "cpd", 0.1), TimedRow(1, "cpd", 0.2), TimedRow(2, "cpd", 0.6),
                 TimedRow(3, "cpd", 0.0)},
                Prov("same.h5"),
                ""};
    const Table t =
        BuildTimingTable({s}, LoadPaperTables(DefaultPaperTablesPath()), "Test CPU", "OpenBLAS", kPaperRows);
    ASSERT_EQ(t.rows.size(), 1u);
    // CPU milliseconds of the calls (not their wall seconds, twice as long here).
    EXPECT_NEAR(t.rows[0].Get("cpu_ms_mean").value, 300.0, 1e-12);
    EXPECT_DOUBLE_EQ(t.rows[0].Get("cpu_ms_median").value, 200.0);
    EXPECT_EQ(t.rows[0].Get("cpu_ms_mean").pairs, 3u);
    // Issue 54, item 7: the points the timed calls had (the rows'), not the 1024 the pair
    // file sampled before cropping.
    EXPECT_DOUBLE_EQ(t.rows[0].Get("points").value, 717);
    EXPECT_EQ(t.rows[0].Get("points").text, "");
    EXPECT_DOUBLE_EQ(t.rows[0].Get("paper:ms").value, 4347.0);  // Tab. 6 CPD, 4.347 s
    EXPECT_NE(t.caption.find("Test CPU"), std::string::npos);
    EXPECT_NE(t.caption.find("OpenBLAS"), std::string::npos);
    // The timing table carries the CCD floor of its pairs too.
    ASSERT_EQ(t.notes.size(), 1u);
    EXPECT_NE(t.notes[0].find("0.1041"), std::string::npos) << t.notes[0];
}

// Tab. 6's points: a range where the timed calls' clouds differ (a target of another size, a
// downsampled call), blank where the rows do not record them (never the pair file's count).
TEST(PaperReport, TimingTablePointsComeFromTheRows) {
    ResultRow other = TimedRow(1, "cpd", 0.2);
    other.target_points = 700;
    ResultRow old_icp = TimedRow(0, "icp", 0.1);
    old_icp.source_points.reset();
    old_icp.target_points.reset();
    const ResultSet s{"", {TimedRow(0, "cpd", 0.1), other, old_icp}, Prov("same.h5"), ""};
    const Table t = BuildTimingTable({s}, LoadPaperTables(DefaultPaperTablesPath()), "Test CPU",
                                     "OpenBLAS", kPaperRows);
    ASSERT_EQ(t.rows.size(), 2u);
    EXPECT_EQ(t.rows[0].label, "cpd");
    EXPECT_EQ(t.rows[0].Get("points").text, "700-717");
    EXPECT_EQ(t.rows[1].label, "icp");
    EXPECT_FALSE(t.rows[1].Get("points").HasValue());
    EXPECT_NE(TablesToMarkdown({t}).find("| 700-717 |"), std::string::npos)
        << TablesToMarkdown({t});
}

TEST(PaperReport, TimingTableShowsTheLearnedRowsFloorAndTheFullAttentionRow) {
    // ogmm (clustered) and deepgmr on the pairs, plus a set labelled OGMM_full_attention (ogmm
    // with full attention, as reproduce's timing variant) on the same pair file.
    ResultSet rows{
        "",
        {TimedRow(0, "cpd", 0.01), TimedRow(1, "cpd", 0.03),
         TimedRow(0, "ogmm", 0.2, 0.12, 2.5e9, 0.05), TimedRow(1, "ogmm", 0.3, 0.18, 2.5e9, 0.05),
         TimedRow(0, "deepgmr", 0.1, 0.06, 1.5e9, 0.03)},
        Prov("same.h5"),
        ""};
    ResultSet full{
        "",
        {TimedRow(0, "ogmm", 0.3, 0.2, 3.4e9, 0.07), TimedRow(1, "ogmm", 0.3, 0.22, 3.4e9, 0.07)},
        Prov("same.h5"),
        "OGMM_full_attention"};
    const Table t = BuildTimingTable({rows, full}, LoadPaperTables(DefaultPaperTablesPath()),
                                     "Test CPU", "Eigen", kPaperRows);
    for (const char* key : {"gmac", "floor_ms", "x_floor", "network_ms"}) {
        EXPECT_NO_THROW(Col(t, key)) << key;
    }
    std::vector<std::string> headers;
    for (const auto& c : t.columns) headers.push_back(c.header);
    for (const char* h : {"GMAC", "floor ms", "x floor"}) {
        EXPECT_NE(std::find(headers.begin(), headers.end(), h), headers.end()) << h;
    }
    const auto cell = [&](const std::string& row, const std::string& col) {
        return RowNamed(t, row).Get(col);
    };
    // ogmm: network 150 ms mean, 2.5 GMAC, floor 50 ms, x floor 3; the paper's clustered row.
    EXPECT_NEAR(cell("ogmm", "cpu_ms_mean").value, 250.0, 1e-9);
    EXPECT_NEAR(cell("ogmm", "network_ms").value, 150.0, 1e-9);
    EXPECT_NEAR(cell("ogmm", "gmac").value, 2.5, 1e-12);
    EXPECT_NEAR(cell("ogmm", "floor_ms").value, 50.0, 1e-9);
    EXPECT_NEAR(cell("ogmm", "x_floor").value, 3.0, 1e-12);
    EXPECT_DOUBLE_EQ(cell("ogmm", "paper:ms").value, 6.0);  // OGMM_clustered_attention
    // The full-attention row: its own label, 210 / 70 = 3x its floor, beside the paper's 47 ms.
    EXPECT_NEAR(cell("OGMM_full_attention", "gmac").value, 3.4, 1e-12);
    EXPECT_NEAR(cell("OGMM_full_attention", "x_floor").value, 3.0, 1e-12);
    EXPECT_DOUBLE_EQ(cell("OGMM_full_attention", "paper:ms").value, 47.0);
    EXPECT_NEAR(cell("deepgmr", "x_floor").value, 2.0, 1e-12);
    EXPECT_DOUBLE_EQ(cell("deepgmr", "paper:ms").value, 2.0);
    // A classical row has its times and blank MAC cells.
    EXPECT_NEAR(cell("cpd", "cpu_ms_mean").value, 20.0, 1e-9);
    for (const char* key : {"network_ms", "gmac", "floor_ms", "x_floor"}) {
        EXPECT_FALSE(cell("cpd", key).HasValue()) << key;
    }
    const std::string md = TableToMarkdown(t);
    EXPECT_NE(md.find("| GMAC | floor ms | x floor |"), std::string::npos) << md;
    EXPECT_NE(md.find("| OGMM_full_attention |"), std::string::npos) << md;
    const std::size_t at = md.find("| cpd |");
    ASSERT_NE(at, std::string::npos) << md;
    const std::string cpd_line = md.substr(at, md.find('\n', at) - at);
    EXPECT_NE(cpd_line.find("| - | - | - | - |"), std::string::npos) << cpd_line;
    // The machine: CPU model, the learned rows' BLAS and GEMM rate, the classical methods'.
    // The rows' rates differ (50 and 48.6 GMAC/s, as several processes' would: the shards of
    // reproduce --shard): the BLAS is named once, with their range.
    EXPECT_NE(t.caption.find("Test CPU"), std::string::npos) << t.caption;
    EXPECT_NE(t.caption.find("TestBLAS 1.0 (pthreads) at 48.6-50.0 GMAC/s single-thread"),
              std::string::npos)
        << t.caption;
    EXPECT_EQ(t.caption.find("TestBLAS", t.caption.find("TestBLAS") + 1), std::string::npos)
        << t.caption;
    EXPECT_NE(t.caption.find("Eigen"), std::string::npos) << t.caption;
    // One pair file: one provenance and one CCD floor note.
    EXPECT_EQ(t.provenance.size(), 1u);
    EXPECT_EQ(t.notes.size(), 1u);
}

TEST(PaperReport, CompleteTableOffersTheCleanSharedVariantBesideThePapersC2c) {
    Provenance noisy = Prov("c2c.h5");
    noisy.protocol = "complete";
    noisy.selection = "cycle";
    noisy.noise_sigma = 0.01;
    noisy.gt_ccd_floor = 0.0512;
    Provenance clean = noisy;
    clean.pairs_file = "c2c_clean.h5";
    clean.pairing = "shared";
    clean.noise_sigma = 0.0;
    clean.gt_ccd_floor = 0.0;
    const ResultSet a{"c2c", {Row(0, "cpd", 2.0), Row(1, "cpd", 4.0)}, noisy, ""};
    const ResultSet b{"c2c_clean", {Row(0, "cpd", 0.5), Row(1, "cpd", 1.5)}, clean, ""};
    const Table t = BuildPaperTable(FindPaperTableSpec("supp_complete"), {a, b},
                                    LoadPaperTables(DefaultPaperTablesPath()), Options());
    const TableRow& cpd = RowNamed(t, "CPD");
    // Hand: (2 + 4) / 2 = 3 and (0.5 + 1.5) / 2 = 1.
    EXPECT_DOUBLE_EQ(cpd.Get("c2c.mae_r").value, 3.0);
    EXPECT_DOUBLE_EQ(cpd.Get("c2c_clean.mae_r").value, 1.0);
    // The clean columns sit beside the paper's c2c cells (CPD 0.8171 deg, CCD 0.0037 as
    // transcribed in data/paper/ogmm_wacv2023_tables.json), and say so in the header.
    EXPECT_DOUBLE_EQ(cpd.Get("paper:c2c_clean.mae_r").value, 0.8171);
    EXPECT_DOUBLE_EQ(cpd.Get("paper:c2c_clean.ccd").value, 0.0037);
    EXPECT_EQ(t.columns[Col(t, "paper:c2c_clean.mae_r")].header, "paper MAE(R) c2c");
    EXPECT_FALSE(cpd.Get("c2p.mae_r").HasValue());  // no c2p rows given
    // Caption: each group's pairing and noise; notes: each group's floor.
    EXPECT_NE(t.caption.find("pairing shared"), std::string::npos) << t.caption;
    EXPECT_NE(t.caption.find("noise-free"), std::string::npos) << t.caption;
    EXPECT_NE(t.caption.find("noise sigma 0.01"), std::string::npos) << t.caption;
    ASSERT_EQ(t.notes.size(), 2u);
    EXPECT_NE(t.notes[0].find("(c2c): 0.0512"), std::string::npos) << t.notes[0];
    EXPECT_NE(t.notes[1].find("(c2c_clean): 0.0000"), std::string::npos) << t.notes[1];
    // CSV / JSON carry the selection and the noise of the pairs behind each measured cell.
    const nlohmann::json j = TablesToJson({t});
    bool seen = false;
    for (const auto& rec : j) {
        if (rec["row"] == "CPD" && rec["column"] == "c2c_clean.mae_r") {
            seen = true;
            EXPECT_EQ(rec["selection"], "cycle");
            EXPECT_EQ(rec["noise_sigma"], 0.0);
            EXPECT_EQ(rec["pairing"], "shared");
        }
    }
    EXPECT_TRUE(seen);
    const auto csv = ParseCsv(TablesToCsv({t}));
    EXPECT_NE(std::find(csv[0].begin(), csv[0].end(), "noise_sigma"), csv[0].end());
    EXPECT_NE(std::find(csv[0].begin(), csv[0].end(), "selection"), csv[0].end());
}

TEST(PaperReport, TableWithoutPairsSaysItsFloorIsUnknown) {
    const Table t = BuildPaperTable(FindPaperTableSpec("table4_ablation_components"), {},
                                    LoadPaperTables(DefaultPaperTablesPath()), Options());
    ASSERT_EQ(t.notes.size(), 1u);
    EXPECT_NE(t.notes[0].find("CCD floor: not known"), std::string::npos) << t.notes[0];
}

// An ablation's variants run on the same pairs. Its table described the same data once per
// variant and printed one identical floor note per variant (found 2026-12-04 in
// `reproduce --tables table4`: four copies of each). Expected, by hand: one description naming
// every variant, one floor note; a variant on other pairs keeps its own description.
TEST(PaperReport, AblationVariantsOnTheSamePairsAreDescribedOnce) {
    const auto set = [](const std::string& label, const std::string& file) {
        return ResultSet{"", {Row(0, "ogmm", 1.0), Row(1, "ogmm", 2.0)}, Prov(file), label};
    };
    const Table t = BuildPaperTable(
        FindPaperTableSpec("table4_ablation_components"),
        {set("full", "p.h5"), set("no_SPE", "p.h5"), set("no_CSA", "p.h5"), set("no_OSP", "q.h5")},
        LoadPaperTables(DefaultPaperTablesPath()), Options());
    EXPECT_NE(t.caption.find("ours / full, no_SPE, no_CSA: dataset `cgal`"), std::string::npos)
        << t.caption;
    EXPECT_NE(t.caption.find("; ours / no_OSP: dataset `cgal`"), std::string::npos) << t.caption;
    const auto count = [&](const std::string& what) {
        std::size_t n = 0;
        for (auto at = t.caption.find(what); at != std::string::npos;
             at = t.caption.find(what, at + 1))
            ++n;
        return n;
    };
    EXPECT_EQ(count("dataset `cgal`"), 2u) << t.caption;
    ASSERT_EQ(t.notes.size(), 1u);
    EXPECT_NE(t.notes[0].find("Ground-truth CCD floor: 0.1041"), std::string::npos) << t.notes[0];
}

// The cluster-count table's columns (groups 32, 8, 64) are variants on one pair file. Its
// table printed one floor note per column, identical but for the group (found 2026-12-04 in
// `reproduce --tables supp_cluster`). Expected, by hand: one note naming the three groups.
TEST(PaperReport, GroupsOnTheSamePairsShareOneFloorNote) {
    const auto set = [](const std::string& group) {
        return ResultSet{group, {Row(0, "ogmm", 1.0), Row(1, "ogmm", 2.0)}, Prov("p.h5"), ""};
    };
    const Table t =
        BuildPaperTable(FindPaperTableSpec("supp_cluster_count"), {set("32"), set("8"), set("64")},
                        LoadPaperTables(DefaultPaperTablesPath()), Options());
    ASSERT_EQ(t.notes.size(), 1u);
    EXPECT_NE(t.notes[0].find("Ground-truth CCD floor (32, 8, 64): 0.1041"), std::string::npos)
        << t.notes[0];
}

}  // namespace
}  // namespace regbench
