#include "reports/paper_tables.hpp"

#include <gtest/gtest.h>

namespace regbench {
namespace {

TEST(PaperTables, ComparisonPutsThePaperCellNextToOurs) {
    const nlohmann::json paper = LoadPaperTables(DefaultPaperTablesPath());
    MethodSummary cpd;
    cpd.method = "cpd";
    cpd.mae_r.mean = 1.5;
    MethodSummary mine;
    mine.method = "identity";
    const std::string md =
        FormatPaperComparison({cpd, mine}, paper, "table1_modelnet_partial", "cross_category");
    // Paper Tab. 1 cross-category CPD: MAE(R) 12.681, MAE(t) 0.1153, CCD 0.1154; Tab. 6: 4.347 s.
    EXPECT_NE(md.find("| cpd | 1.5000 | 12.681 |"), std::string::npos) << md;
    EXPECT_NE(md.find("0.1153"), std::string::npos);
    EXPECT_NE(md.find("4.347"), std::string::npos);
    EXPECT_NE(md.find("| identity | 0.0000 | - |"), std::string::npos) << md;
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
