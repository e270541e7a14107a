// Experiment files: the embedded paper plan parses and says what the paper's tables need, and
// a malformed file is refused naming the file and the key.
#include "experiments/experiment_file.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "reports/paper_tables.hpp"
#include "tests/testing/temp_dir_test.hpp"

namespace regbench {
namespace {

TEST(PaperPlan, HasOneFilePerTableInThePapersOrder) {
    std::vector<std::string> tables;
    for (const auto& f : PaperPlan()) tables.push_back(f.table);
    // Tab. 1-6, then the supplementary tables (the paper's order).
    EXPECT_EQ(tables,
              (std::vector<std::string>{
                  "table1_modelnet_partial", "table2_modelnet_noise_density", "table3_indoor",
                  "table4_ablation_components", "table5_ablation_losses", "table6_inference_time",
                  "supp_overlap_ratio", "supp_cluster_count", "supp_complete"}));
    for (const auto& f : PaperPlan()) {
        // A learned method is listed where the paper has its row (data/paper/
        // ogmm_wacv2023_tables.json): OMNET, RGM and REGTR in Tab. 1-3, RIENet in Tab. 1 and 2.
        // (Tab. 6 times every method of tab1_same, listed or not.)
        const bool rienet =
            f.table == "table1_modelnet_partial" || f.table == "table2_modelnet_noise_density";
        const bool omnet = rienet || f.table == "table3_indoor";
        std::vector<std::string> learned = {"ogmm", "deepgmr"};
        if (omnet) learned.push_back("omnet");
        if (rienet) learned.push_back("rienet");
        if (omnet) learned.push_back("rgm");  // the same tables as OMNET
        if (omnet) learned.push_back("regtr");  // REGTR has the rows OMNET has
        EXPECT_EQ(f.learned, learned) << f.file;
        // The cluster-count table is OGMM's alone: its columns are OGMM variants.
        if (f.table == "supp_cluster_count") {
            EXPECT_EQ(f.methods, std::vector<std::string>{"ogmm"});
            continue;
        }
        EXPECT_TRUE(f.methods.empty()) << f.file << ": the paper's tables run every method";
    }
}

TEST(PaperPlan, VariantsAreThePapersAblationRows) {
    const nlohmann::json paper = LoadPaperTables(DefaultPaperTablesPath());
    for (const auto& f : PaperPlan()) {
        if (f.variants.pairs_of.empty()) continue;
        if (f.variants.rows_are_groups) {
            // Cluster counts: the variants and the experiment's own group are the paper's
            // columns (J = 32 is the shipped ogmm-small's).
            std::vector<std::string> ours = {f.experiments.at(0).group}, papers;
            for (const auto& r : f.variants.rows) ours.push_back(r.row);
            for (const auto& c : paper["tables"][f.table]["columns"]) papers.push_back(c);
            EXPECT_EQ(f.variants.pairs_of, f.experiments.at(0).id);
            std::sort(ours.begin(), ours.end());
            std::sort(papers.begin(), papers.end());
            EXPECT_EQ(ours, papers) << f.table;
            continue;
        }
        std::vector<std::string> ours, papers;
        for (const auto& r : f.variants.rows) ours.push_back(r.row);
        for (const auto& r : paper["tables"][f.table]["row_order"]) papers.push_back(r);
        std::sort(ours.begin(), ours.end());
        std::sort(papers.begin(), papers.end());
        EXPECT_EQ(ours, papers) << f.table;
        EXPECT_EQ(f.variants.pairs_of, "tab1_same") << f.table;
        EXPECT_EQ(f.variants.method, "ogmm");
        EXPECT_EQ(f.variants.model, "ogmm-small");
    }
}

TEST(PaperPlan, Tab6TimesOgmmWithFullAttentionOnTab1sPairs) {
    for (const auto& f : PaperPlan()) {
        if (f.table != "table6_inference_time") continue;
        EXPECT_EQ(f.timing_of, "tab1_same");
        ASSERT_EQ(f.timing_variants.size(), 1u);
        const TimingVariant& v = f.timing_variants[0];
        // The paper's row name, so its 0.047 s sits beside it.
        EXPECT_EQ(v.row, "OGMM_full_attention");
        EXPECT_EQ(v.method, "ogmm");
        EXPECT_EQ(v.params, (nlohmann::json{{"attention", "full"}}));
        const nlohmann::json paper = LoadPaperTables(DefaultPaperTablesPath());
        EXPECT_TRUE(paper["tables"][f.table]["rows"].contains(v.row));
        return;
    }
    FAIL() << "no table6_inference_time in the plan";
}

/// The variants `regbench train --ablation` trained before they were data (app/cmd_train.cpp).
TEST(PaperPlan, VariantConfigsAreTheTrainedOnes) {
    std::map<std::string, std::vector<std::pair<std::string, nlohmann::json>>> kinds;
    for (const auto& f : PaperPlan()) {
        if (f.variants.rows.empty()) continue;
        for (const auto& r : f.variants.rows) kinds[f.variants.kind].push_back({r.row, r.config});
    }
    ASSERT_EQ(kinds.size(), 3u);
    using V = std::vector<std::pair<std::string, nlohmann::json>>;
    EXPECT_EQ(kinds["components"], (V{{"full", nlohmann::json::object()},
                                      {"no_SPE", {{"spe", false}}},
                                      {"no_CSA", {{"csa", false}}},
                                      {"no_OSP", {{"osp", false}}}}));
    const auto loss = [](bool gr, bool cl, bool os) {
        return nlohmann::json{{"w_pose", gr ? 10.0 : 0.0},
                              {"w_welsch", gr ? 0.01 : 0.0},
                              {"w_clu", cl ? 1.0 : 0.0},
                              {"w_ovl", os ? 1.0 : 0.0}};
    };
    EXPECT_EQ(kinds["losses"], (V{{"GR", loss(true, false, false)},
                                  {"CL", loss(false, true, false)},
                                  {"OS", loss(false, false, true)},
                                  {"GR+CL", loss(true, true, false)},
                                  {"CL+OS", loss(false, true, true)},
                                  {"GR+OS", loss(true, false, true)},
                                  {"GR+CL+OS", loss(true, true, true)}}));
    // J = 32 is ogmm-small itself (the shipped ogmm fills that column).
    EXPECT_EQ(kinds["clusters"], (V{{"8", {{"clusters", 8}}},
                                    {"16", {{"clusters", 16}}},
                                    {"48", {{"clusters", 48}}},
                                    {"64", {{"clusters", 64}}}}));
    // Floats stay floats: the checkpoints record the config as trained (10.0, not 10).
    EXPECT_TRUE(kinds["losses"][0].second["w_pose"].is_number_float());
}

using ExperimentFileTest = testing::TempDirTest;

/// The message ReadExperimentFile refuses `text` with.
std::string Refusal(const std::string& path, const std::string& text) {
    std::ofstream(path) << text;
    try {
        (void)ReadExperimentFile(path);
    } catch (const std::exception& e) {
        return e.what();
    }
    return "(accepted)";
}

TEST_F(ExperimentFileTest, MalformedFilesAreRefusedNamingFileAndKey) {
    const std::string path = Path("mine.json");
    const std::string head = R"({"table": "mine", "title": "Mine", )";
    const std::string good =
        R"("id": "a", "protocol": "partial", "split": "test", "dataset": "procedural")";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"{\"table\": ", "not valid JSON"},
        {"[1, 2]", "parameters must be a JSON object"},
        {R"({"title": "x", "experiments": []})", ": parameter 'table' is required"},
        {head + R"("experiment": []})", ": unknown parameter 'experiment'"},
        {head + R"("experiments": {"id": "a"}})", ": parameter 'experiments' expects array"},
        {head + R"("experiments": [{"id": "a"}]})",
         ": experiments[0]: parameter 'protocol' is required"},
        {head + R"("experiments": [{)" + good + R"(, "pairs": {"count": 2.5}}]})",
         ": experiments[0]: pairs: parameter 'count' must be a whole number"},
        {head + R"("experiments": [{)" + good + R"(, "pairs": 3}]})",
         ": experiments[0]: pairs: parameters must be a JSON object, got 3"},
        {head + R"("experiments": [{)" + good + R"(, "pairs": {"scale": -1}}]})",
         ": experiments[0]: pairs: parameter 'scale' must be in (0, 1e6]"},
        {head + R"("experiments": [{"id": "a", "protocol": "parital", "split": "test", )" +
             R"("dataset": "procedural"}]})",
         ": experiments[0]: parameter 'protocol' is not valid: unknown protocol 'parital'"},
        {head + R"("experiments": [{)" + good + R"(, "root": "modelnet"}]})",
         ": experiments[0]: parameter 'root' must be modelnet40, 7scenes or icl-nuim"},
        {head + R"("methods": "icp", "experiments": [{)" + good + "}]}",
         ": parameter 'methods' expects array"},
        {head + R"("variants": {"kind": "k", "method": "ogmm", "model": "m", )" +
             R"("rows": [{"row": "r", "config": 3}]}})",
         ": variants: rows[0]: parameter 'config' expects object, got 3"},
        {head + "\"caption\": \"c\"}", ": parameter 'experiments' is required"},
        {head + R"("experiments": [{)" + good + R"(, "protocol_options": {"bogus": 1}}]})",
         ": experiments[0]: parameter 'protocol_options' is not valid: protocol options: "
         "unknown parameter 'bogus'"},
        {head + R"("experiments": [{)" + good + R"(, "protocol_options": {"keep": 1.5}}]})",
         ": experiments[0]: parameter 'protocol_options' is not valid: "},
        {head + R"("experiments": [{)" + good + R"(, "protocol_options": 3}]})",
         ": experiments[0]: parameter 'protocol_options' expects object, got 3"},
        {head + R"("experiments": [{)" + good +
             R"(}], "timing_variants": [{"row": "r", "method": "ogmm"}]})",
         ": parameter 'timing_variants' needs timing_of"},
        {head + R"("timing_of": "a", "experiments": [{)" + good +
             R"(}], "timing_variants": [{"row": "r"}]})",
         ": timing_variants[0]: parameter 'method' is required"},
        {head + R"("timing_of": "a", "experiments": [{)" + good +
             R"(}], "timing_variants": [{"row": "r", "method": "ogmm", "params": 3}]})",
         ": timing_variants[0]: parameter 'params' expects object, got 3"},
    };
    for (const auto& [text, expected] : cases) {
        const std::string message = Refusal(path, text);
        EXPECT_NE(message.find("experiment file " + path), std::string::npos) << message;
        EXPECT_NE(message.find(expected), std::string::npos) << text << "\n-> " << message;
    }
}

TEST_F(ExperimentFileTest, ReferencesAndIdsAreCheckedAcrossTheRunsFiles) {
    const auto file = [](std::string table, std::string id, std::string timing_of) {
        ExperimentFile f;
        f.file = table + ".json";
        f.table = table;
        f.experiments.push_back({});
        f.experiments.back().id = id;
        f.timing_of = timing_of;
        return f;
    };
    EXPECT_NO_THROW(CheckExperimentFiles({file("a", "x", ""), file("b", "y", "x")}));
    const auto refusal = [](const std::vector<ExperimentFile>& files) -> std::string {
        try {
            CheckExperimentFiles(files);
        } catch (const std::exception& e) {
            return e.what();
        }
        return "(accepted)";
    };
    EXPECT_EQ(refusal({file("a", "x", ""), file("b", "y", "z")}),
              "experiment file b.json: parameter 'timing_of' names experiment 'z', which no "
              "file of this run has");
    EXPECT_EQ(refusal({file("a", "x", ""), file("b", "x", "")}),
              "experiment file b.json: parameter 'experiments' repeats id 'x' of a.json");
    EXPECT_EQ(refusal({file("a", "x", ""), file("a", "y", "")}),
              "experiment file a.json: parameter 'table' names table 'a', which another file of "
              "this run fills too");
}

}  // namespace
}  // namespace regbench
