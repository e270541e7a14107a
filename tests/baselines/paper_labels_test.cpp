// Each method names the row of the OGMM paper's tables it fills (MethodInfo::paper_label); the
// reports take those names from the registry (runners/registry.hpp PaperRowLabels) and name no
// method themselves. The independent side is the paper's own table file.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "core/data_dir.hpp"
#include "runners/registry.hpp"

namespace regbench {
namespace {

nlohmann::json Table1Rows() {
    std::ifstream in(DataDir() + "/paper/ogmm_wacv2023_tables.json");
    return nlohmann::json::parse(in).at("tables").at("table1_modelnet_partial").at("rows");
}

TEST(PaperLabels, EveryLabelIsARowOfThePaperAndNoRowIsFilledTwice) {
    const nlohmann::json rows = Table1Rows();
    std::map<std::string, std::string> filled_by;
    for (const auto& [method, label] : PaperRowLabels()) {
        EXPECT_TRUE(rows.contains(label)) << method << ": '" << label << "' is no row of Tab. 1";
        EXPECT_TRUE(filled_by.emplace(label, method).second)
            << "'" << label << "' is filled by " << filled_by[label] << " and " << method;
    }
    // The classical rows of Tab. 1, as the paper spells them (its file's row names).
    for (const char* row : {"ICP", "FGR", "CPD", "GMMReg", "SVR", "FilterReg"}) {
        EXPECT_EQ(filled_by.count(row), 1u) << row << " is filled by no method";
    }
    EXPECT_EQ(filled_by["CPD"], "cpd");
}

TEST(PaperLabels, VariantsTheTableDoesNotShowHaveNone) {
    // The paper's rows are its methods as published: the -noicp variants regbench adds, and
    // methods the paper did not run (gicp, ndt, identity), fill no row of it.
    const auto labels = PaperRowLabels();
    for (const auto& m : AllMethods()) {
        const bool noicp = m.name.size() > 6 && m.name.substr(m.name.size() - 6) == "-noicp";
        if (noicp || m.name == "gicp" || m.name == "identity") {
            EXPECT_EQ(labels.count(m.name), 0u) << m.name;
        }
    }
}

}  // namespace
}  // namespace regbench
