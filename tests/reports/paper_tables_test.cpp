#include "reports/paper_tables.hpp"

#include <gtest/gtest.h>

namespace regbench {
namespace {

/// The OGMM paper's row name of CPD (its tables spell it so); the registry's own labels are
/// checked against the paper's file in tests/baselines (PaperLabels.*).
const PaperRows kPaperRows = {{"cpd", "CPD"}};

/// Our side: cpd (MAE(R) 1.5, CI [1, 2]) and identity (all zero), each over `pairs` pairs.
ReportTable CpdAndIdentity(std::size_t pairs) {
    ReportTable ours;
    ours.methods.resize(2);
    ours.methods[0].method = "cpd";
    ours.methods[0].mae_r = {1.5, 1.0, 2.0};
    ours.methods[1].method = "identity";
    for (auto& m : ours.methods) m.pairs = pairs;
    return ours;
}

TEST(PaperTables, ComparisonPutsThePaperCellNextToOurs) {
    const nlohmann::json paper = LoadPaperTables(DefaultPaperTablesPath());
    const ReportTable ours = CpdAndIdentity(30);
    const Table t = PaperComparisonTable(ours, paper, "table1_modelnet_partial", "cross_category", kPaperRows);
    const std::string md = TableToMarkdown(t, TableForm::kFull);
    // Paper Tab. 1 cross-category CPD: MAE(R) 12.681, MAE(t) 0.1153, CCD 0.1154; Tab. 6: 4.347 s.
    // Issue 26: the pairs column (ours: 30) says what our means are over.
    EXPECT_NE(md.find("| method | pairs | mae_r |"), std::string::npos) << md;
    // Every quantity in its one format: MAE(R) 4 decimals, seconds 5, the paper's as ours.
    EXPECT_NE(md.find("| cpd | 30 | 1.5000 ± 0.5000 | 12.6810 |"), std::string::npos) << md;
    EXPECT_NE(md.find("0.1153"), std::string::npos);
    EXPECT_NE(md.find("4.34700"), std::string::npos);
    EXPECT_NE(md.find("| identity | 30 | 0.0000 ± 0.0000 | - |"), std::string::npos) << md;
    // Compact (issue 41 item 4): mean±CI rounded to the CI (half-width 0.5: two significant
    // digits, 2 decimals) with the paper's number as transcribed beside it in one cell.
    const std::string compact = TableToMarkdown(t);
    EXPECT_NE(compact.find("| method | pairs | mae_r (paper) |"), std::string::npos) << compact;
    EXPECT_NE(compact.find("| cpd | 30 | 1.50±0.50 (12.681) |"), std::string::npos) << compact;
}

TEST(PaperTables, EveryFormatCarriesThePapersCellsAndOurPairs) {
    // Issue 26: --paper was dropped silently with --format csv|latex|json.
    const nlohmann::json paper = LoadPaperTables(DefaultPaperTablesPath());
    const ReportTable ours = CpdAndIdentity(10);
    const Table t = PaperComparisonTable(ours, paper, "table1_modelnet_partial", "cross_category", kPaperRows);
    const std::string csv = TablesToCsv({t});
    // Same cells as the Markdown test above (the paper's JSON), one record each.
    for (const char* record :
         {",cpd,pairs,pairs,measured,10,", ",cpd,mae_r,mae_r,measured,1.5,",
          ",cpd,paper:mae_r,paper mae_r,paper,12.681,",
          ",cpd,paper:mae_t,paper mae_t,paper,0.1153,", ",cpd,paper:ccd,paper ccd,paper,0.1154,",
          ",cpd,paper:seconds,paper s,paper,4.347,", ",identity,pairs,pairs,measured,10,",
          ",identity,paper:mae_r,paper mae_r,paper,,"}) {
        EXPECT_NE(csv.find("paper:table1_modelnet_partial:cross_category" + std::string(record)),
                  std::string::npos)
            << record << "\n"
            << csv;
    }
    const nlohmann::json j = TablesToJson({t});
    EXPECT_EQ(j[0]["pairs"], 10);
    EXPECT_DOUBLE_EQ(j[2]["value"].get<double>(), 12.681);
    EXPECT_EQ(j[2]["column"], "paper:mae_r");
    EXPECT_TRUE(j[11]["value"].is_null());  // identity's paper mae_r: the paper has none
    EXPECT_EQ(j[11]["column"], "paper:mae_r");
    const std::string tex = TableToLatex(t);
    EXPECT_NE(tex.find("cpd & 10 & 1.5000 $\\pm$ 0.5000 & 12.6810"), std::string::npos) << tex;
    EXPECT_NE(tex.find("\\toprule"), std::string::npos) << tex;
}

TEST(PaperTables, UnknownTableOrGroupListsTheValidOnes) {
    const nlohmann::json paper = LoadPaperTables(DefaultPaperTablesPath());
    try {
        PaperComparisonTable({}, paper, "table9", "", kPaperRows);
        FAIL();
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("table1_modelnet_partial"), std::string::npos);
    }
    EXPECT_THROW(PaperComparisonTable({}, paper, "table1_modelnet_partial", "nosuch", kPaperRows),
                 std::invalid_argument);
    EXPECT_THROW(LoadPaperTables("/nonexistent.json"), std::runtime_error);
}

}  // namespace
}  // namespace regbench
