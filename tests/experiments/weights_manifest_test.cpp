// The weights manifest (experiments/weights_manifest.hpp): its form, the order in which entries
// apply, and the shipped default (data/models/weights.json): Tab. 3's OGMM, DeepGMR, OMNet and
// REGTR rows run the indoor-trained checkpoints, every other cell the method's own shipped folder.
#include "experiments/weights_manifest.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "baselines/learned.hpp"
#include "experiments/experiment_file.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;

/// Every experiment of the paper's plan with every method its table runs (as reproduce asks).
std::vector<WeightsTarget> PaperTargets() {
    std::vector<std::string> all;
    for (const auto& m : LearnedMethodInfos()) all.push_back(m.name);
    all.push_back("icp");
    std::vector<WeightsTarget> targets;
    for (const auto& f : PaperPlan()) {
        for (const auto& e : f.experiments) {
            targets.push_back({e.id, f.table, f.methods.empty() ? all : f.methods});
        }
    }
    return targets;
}

TEST(WeightsManifest, ShippedDefaultRunsEachTablesOwnCheckpoints) {
    const std::string path = DefaultWeightsManifestPath();
    ASSERT_FALSE(path.empty());
    std::ostringstream log;
    const WeightsPlan plan =
        ResolveWeights(ReadWeightsManifest(path), PaperTargets(), testing::TempPath("w"), log);
    // data/models/weights.json: Tab. 3's columns run the indoor fine-tunes (OGMM, DeepGMR,
    // OMNet and REGTR; RGM's object checkpoint, docs/learned-methods.md), Tab. 1's
    // cross-category column the OGMM and DeepGMR models trained on the other categories.
    const std::vector<std::string> tab3 = {"ogmm",          "ogmm-noicp", "deepgmr",
                                           "deepgmr-noicp", "omnet",      "regtr"};
    const std::vector<std::string> cross = {"ogmm", "ogmm-noicp", "deepgmr", "deepgmr-noicp"};
    const std::map<std::string, std::pair<std::string, std::vector<std::string>>> folder_of = {
        {"tab3_7scenes", {"indoor", tab3}},
        {"tab3_icl_nuim", {"indoor", tab3}},
        {"tab1_cross", {"cross", cross}}};
    for (const auto& [id, entry] : folder_of) {
        const auto& [folder, methods] = entry;
        for (const std::string& method : methods) {
            SCOPED_TRACE(id + " " + method);
            const WeightsChoice& c = plan.at(id).at(method);
            EXPECT_FALSE(c.is_default);
            EXPECT_EQ(c.source, "shipped");
            EXPECT_EQ(fs::path(c.checkpoint).parent_path().filename(), folder);
            EXPECT_EQ(c.sha256.size(), 64u);
        }
        EXPECT_TRUE(plan.at(id).at("rgm").is_default);  // object-trained, as before
    }
    // Every other experiment runs each learned method's own shipped folder: rows unchanged.
    for (const auto& [id, methods] : plan) {
        if (folder_of.count(id) != 0) continue;
        for (const auto& [method, c] : methods) {
            EXPECT_TRUE(c.is_default) << id << " " << method;
            EXPECT_EQ(c.checkpoint, DefaultCheckpointDir(method));
        }
    }
}

// A run of the user's own experiment files keeps of the shipped manifest what applies to it
// (nothing here: it names only Tab. 3), where a user's manifest naming them is refused.
TEST(WeightsManifest, ShippedDefaultKeepsOnlyTheExperimentsOfTheRun) {
    const std::vector<WeightsTarget> mine = {{"mine_partial", "mine", {"ogmm", "icp"}}};
    const WeightsManifest shipped = ReadWeightsManifest(DefaultWeightsManifestPath());
    ASSERT_FALSE(shipped.entries.empty());
    EXPECT_TRUE(OnlyTargetsOf(shipped, mine).entries.empty());
    std::ostringstream log;
    const std::string e = testing::ErrorOf(
        [&] { ResolveWeights(shipped, mine, testing::TempPath("w_mine"), log); });
    EXPECT_NE(e.find("names experiment 'table3_indoor', which this run does not have"),
              std::string::npos)
        << e;
    EXPECT_EQ(OnlyTargetsOf(shipped, PaperTargets()).entries.size(), shipped.entries.size());
}

// A later entry wins for the same (experiment, method); a table id covers its experiments.
TEST(WeightsManifest, LaterEntriesWinAndTablesCoverTheirExperiments) {
    const fs::path dir = testing::FreshTempDir("weights_order");
    const std::string ogmm = DefaultCheckpointDir("ogmm");
    const std::string rgm = DefaultCheckpointDir("rgm");
    std::ofstream(dir / "m.json") << nlohmann::json{
        {"format", "regbench-weights"},
        {"format_version", 1},
        {"entries",
         {{{"experiments", {"table1_modelnet_partial"}},
           {"methods", {"ogmm-noicp"}},
           {"checkpoint", rgm},
           {"label", "first"}},
          {{"experiments", {"tab1_cross"}},
           {"methods", {"ogmm-noicp"}},
           {"checkpoint", ogmm},
           {"label", "second"}}}}}.dump();
    std::ostringstream log;
    const WeightsPlan plan = ResolveWeights(ReadWeightsManifest((dir / "m.json").string()),
                                            PaperTargets(), (dir / "imports").string(), log);
    EXPECT_EQ(plan.at("tab1_same").at("ogmm-noicp").checkpoint, rgm);
    EXPECT_EQ(plan.at("tab1_same").at("ogmm-noicp").label.rfind("first: ", 0), 0u);
    EXPECT_EQ(plan.at("tab1_cross").at("ogmm-noicp").checkpoint, ogmm);
    EXPECT_TRUE(plan.at("tab1_cross").at("ogmm-noicp").is_default);
    EXPECT_FALSE(fs::exists(dir / "imports"));  // no authors' file: nothing imported
}

// The form: unknown keys, a missing source and settings beside a checkpoint folder are refused
// naming the file and the entry.
TEST(WeightsManifest, FormErrorsNameTheFileAndEntry) {
    const fs::path dir = testing::FreshTempDir("weights_form");
    const auto error = [&](const nlohmann::json& entry) {
        std::ofstream(dir / "m.json", std::ios::trunc) << nlohmann::json{
            {"format", "regbench-weights"},
            {"format_version", 1},
            {"entries", {entry}}}.dump();
        return testing::ErrorOf([&] { ReadWeightsManifest((dir / "m.json").string()); });
    };
    std::string e = error({{"experiments", {"tab1_same"}},
                           {"methods", {"ogmm"}},
                           {"checkpoint", "x"},
                           {"weights", "y"}});
    EXPECT_NE(e.find("entry 1: unknown key \"weights\""), std::string::npos) << e;
    e = error({{"experiments", {"tab1_same"}}, {"methods", {"ogmm"}}});
    EXPECT_NE(e.find("needs exactly one of"), std::string::npos) << e;
    e = error({{"experiments", {"tab1_same"}},
               {"methods", {"ogmm"}},
               {"checkpoint", "x"},
               {"preset", "7scenes"}});
    EXPECT_NE(e.find("go with \"authors_file\" only"), std::string::npos) << e;
    e = error(
        {{"experiments", nlohmann::json::array()}, {"methods", {"ogmm"}}, {"checkpoint", "x"}});
    EXPECT_NE(e.find("needs \"experiments\""), std::string::npos) << e;
    EXPECT_NE(e.find((dir / "m.json").string()), std::string::npos) << e;
}

}  // namespace
}  // namespace regbench
