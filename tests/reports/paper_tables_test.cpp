#include "reports/paper_tables.hpp"

#include <gtest/gtest.h>

namespace regbench {
namespace {

TEST(PaperTables, ComparisonPutsThePaperCellNextToOurs) {
    const nlohmann::json paper = LoadPaperTables(DefaultPaperTablesPath());
    MethodSummary cpd;
    cpd.method = "cpd";
    cpd.pairs = 30;
    cpd.mae_r.mean = 1.5;
    MethodSummary mine;
    mine.method = "identity";
    mine.pairs = 30;
    const std::string md =
        FormatPaperComparison({cpd, mine}, paper, "table1_modelnet_partial", "cross_category");
    // Paper Tab. 1 cross-category CPD: MAE(R) 12.681, MAE(t) 0.1153, CCD 0.1154; Tab. 6: 4.347 s.
    // Issue 26: the pairs column (ours: 30) says what our means are over.
    EXPECT_NE(md.find("| method | pairs | mae_r |"), std::string::npos) << md;
    EXPECT_NE(md.find("| cpd | 30 | 1.5000 | 12.681 |"), std::string::npos) << md;
    EXPECT_NE(md.find("0.1153"), std::string::npos);
    EXPECT_NE(md.find("4.347"), std::string::npos);
    EXPECT_NE(md.find("| identity | 30 | 0.0000 | - |"), std::string::npos) << md;
}

TEST(PaperTables, EveryFormatCarriesThePapersCellsAndOurPairs) {
    // Issue 26: --paper was dropped silently with --format csv|latex|json.
    const nlohmann::json paper = LoadPaperTables(DefaultPaperTablesPath());
    MethodSummary cpd;
    cpd.method = "cpd";
    cpd.pairs = 10;
    cpd.mae_r.mean = 1.5;
    MethodSummary mine;
    mine.method = "identity";
    mine.pairs = 10;
    const PaperComparison c =
        BuildPaperComparison({cpd, mine}, paper, "table1_modelnet_partial", "cross_category");
    const std::string csv = FormatPaperComparison(c, "csv");
    EXPECT_NE(csv.find("paper_table,paper_group,method,pairs,mae_r,paper_mae_r,"),
              std::string::npos)
        << csv;
    // Same cells as the Markdown test above (the paper's JSON), absent ones empty.
    EXPECT_NE(csv.find("table1_modelnet_partial,cross_category,cpd,10,1.5,12.681,0,0.1153,0,"
                       "0.1154,0,4.347"),
              std::string::npos)
        << csv;
    EXPECT_NE(csv.find("identity,10,0,,0,,0,,0,\n"), std::string::npos) << csv;
    const nlohmann::json j = ToJson(c);
    EXPECT_EQ(j["rows"][0]["pairs"], 10);
    EXPECT_DOUBLE_EQ(j["rows"][0]["paper_mae_r"].get<double>(), 12.681);
    EXPECT_TRUE(j["rows"][1]["paper_mae_r"].is_null());
    const std::string tex = FormatPaperComparison(c, "latex");
    EXPECT_NE(tex.find("cpd & 10 & 1.5000 & 12.681"), std::string::npos) << tex;
    EXPECT_NE(tex.find("\\toprule"), std::string::npos) << tex;
}

TEST(PaperTables, UnknownTableOrGroupListsTheValidOnes) {
    const nlohmann::json paper = LoadPaperTables(DefaultPaperTablesPath());
    try {
        FormatPaperComparison({}, paper, "table9", "");
        FAIL();
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("table1_modelnet_partial"), std::string::npos);
    }
    EXPECT_THROW(FormatPaperComparison({}, paper, "table1_modelnet_partial", "nosuch"),
                 std::invalid_argument);
    EXPECT_THROW(LoadPaperTables("/nonexistent.json"), std::runtime_error);
}

}  // namespace
}  // namespace regbench
