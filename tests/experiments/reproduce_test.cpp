// The executor: the embedded plan resolves to the experiments the hand-coded plan of
// reports/reproduce.cpp (PlanExperiments, before the plan was data) made, and a user's own
// experiment file runs end to end.
#include "experiments/reproduce.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "runners/result_row.hpp"
#include "tests/testing/temp_dir_test.hpp"

namespace regbench {
namespace {

/// "id table group protocol dataset split pairs seed pairing noise-free one-per-item sweep
/// [fallback]" of every planned experiment.
std::vector<std::string> Plan(const ReproduceOptions& o) {
    std::vector<std::string> out;
    for (const auto& e : PlanExperiments(PaperPlan(), o)) {
        std::string sweep;
        for (const auto& g : e.spec.sweep) sweep += (sweep.empty() ? "" : ",") + g;
        std::ostringstream s;
        s << e.spec.id << " " << e.table << " " << (e.spec.group.empty() ? "-" : e.spec.group)
          << " " << e.spec.protocol << " " << e.dataset << " " << e.spec.split << " " << e.pairs
          << " " << e.seed << " " << (e.pairing.empty() ? "-" : e.pairing) << " "
          << e.spec.noise_free << " " << e.one_per_item << " " << (sweep.empty() ? "-" : sweep)
          << (e.fallback.empty() ? "" : " [" + e.fallback + "]");
        out.push_back(s.str());
    }
    return out;
}

const std::string kMn = " [embedded CGAL mesh corpus instead of ModelNet40]";
const std::string kLevels = "30%,40%,50%,60%,70%";

// Written from the paper's tables and the old PlanExperiments: Tab. 1 same / cross category,
// Tab. 2 jitter / density, Tab. 3 7Scenes / ICL-NUIM (half the pairs, at least 4; ICL-NUIM
// on seed + 1), the overlap sweep (5 levels), the complete-to-complete / -partial table with
// its clean shared-sample c2c variant. Tab. 4-6 use Tab. 1's same-category pairs.
TEST(PlanExperiments, QuickRunOnTheFallbacks) {
    ReproduceOptions o;
    o.quick = true;
    EXPECT_EQ(Plan(o),
              (std::vector<std::string>{
                  "tab1_same table1_modelnet_partial same_category partial cgal "
                  "same_category/test 10 1 - 0 0 -" +
                      kMn,
                  "tab1_cross table1_modelnet_partial cross_category partial cgal "
                  "cross_category/test 10 1 - 0 0 -" +
                      kMn,
                  "tab2_jitter table2_modelnet_noise_density jitter jitter cgal "
                  "same_category/test 10 1 - 0 0 -" +
                      kMn,
                  "tab2_density table2_modelnet_noise_density density density cgal "
                  "same_category/test 10 1 - 0 0 -" +
                      kMn,
                  "tab3_7scenes table3_indoor 7scenes indoor indoor-sim test 5 1 - 0 0 - "
                  "[simulated indoor scans instead of 7Scenes]",
                  "tab3_icl_nuim table3_indoor icl_nuim indoor indoor-sim test 5 2 - 0 0 - "
                  "[simulated indoor scans instead of ICL-NUIM]",
                  "supp_overlap supp_overlap_ratio - overlap-sweep cgal same_category/test 10 1 "
                  "- 0 0 " +
                      kLevels + kMn,
                  // The sweep's 50% level alone, for the cluster-count variants.
                  "supp_clusters supp_cluster_count 32 overlap-sweep cgal same_category/test 10 "
                  "1 - 0 0 -" +
                      kMn,
                  "supp_c2c supp_complete c2c complete cgal same_category/test 10 1 - 0 0 -" + kMn,
                  "supp_c2p supp_complete c2p complete-to-partial cgal same_category/test 10 1 - "
                  "0 0 -" +
                      kMn,
                  "supp_c2c_clean supp_complete c2c_clean complete cgal same_category/test 10 1 "
                  "shared 1 0 -" +
                      kMn,
              }));
}

TEST(PlanExperiments, FullRunOnRealDataUsesEveryTestItemOnce) {
    ReproduceOptions o;
    o.modelnet40 = "/mn";
    o.sevenscenes = "/7s";
    o.icl_nuim = "/icl";
    o.seed = 5;
    o.tables = {"table3", "supp_overlap"};
    EXPECT_EQ(Plan(o),
              (std::vector<std::string>{
                  "tab3_7scenes table3_indoor 7scenes indoor /7s test 500 5 - 0 1 -",
                  // ICL-NUIM's test file's own pairs, as DeepGMR's evaluation.
                  "tab3_icl_nuim table3_indoor icl_nuim indoor /icl test 500 6 stored 0 1 -",
                  "supp_overlap supp_overlap_ratio - overlap-sweep /mn same_category/test "
                  "2500 5 - 0 1 " +
                      kLevels,
              }));
}

TEST(PlanExperiments, PairsOptionScalesEveryExperiment) {
    ReproduceOptions o;
    o.pairs = 7;
    o.modelnet40 = "/mn";
    o.tables = {"table3", "supp_overlap", "table1"};
    const auto plan = Plan(o);
    ASSERT_EQ(plan.size(), 5u);
    EXPECT_EQ(plan[0],
              "tab1_same table1_modelnet_partial same_category partial /mn "
              "same_category/test 7 1 - 0 0 -");
    EXPECT_EQ(plan[2],
              "tab3_7scenes table3_indoor 7scenes indoor indoor-sim test 4 1 - 0 0 - "
              "[simulated indoor scans instead of 7Scenes]");
    EXPECT_EQ(plan[4],
              "supp_overlap supp_overlap_ratio - overlap-sweep /mn same_category/test "
              "17 1 - 0 0 " +
                  kLevels);
}

TEST(PlanExperiments, TablesUseTab1sPairsWhereThePaperDoes) {
    const auto ids = [](std::vector<std::string> tables) {
        ReproduceOptions o;
        o.tables = std::move(tables);
        std::vector<std::string> out;
        for (const auto& e : PlanExperiments(PaperPlan(), o)) out.push_back(e.spec.id);
        return out;
    };
    using Ids = std::vector<std::string>;
    EXPECT_EQ(ids({"table4"}), Ids{"tab1_same"});
    EXPECT_EQ(ids({"table5"}), Ids{"tab1_same"});
    EXPECT_EQ(ids({"table6"}), Ids{"tab1_same"});
    EXPECT_EQ(ids({"table1"}), (Ids{"tab1_same", "tab1_cross"}));
    EXPECT_EQ(ids({"supp_cluster"}), Ids{"supp_clusters"});
    EXPECT_EQ(ids({"supp"}),
              (Ids{"supp_overlap", "supp_clusters", "supp_c2c", "supp_c2p", "supp_c2c_clean"}));
    EXPECT_EQ(ReproducibleTables().size(), 9u);
}

using UserExperiment = testing::TempDirTest;

TEST_F(UserExperiment, RunsEndToEndAndResumes) {
    std::ofstream(Path("mine.json")) << R"({
      "table": "my_table", "title": "My table", "caption": "Two methods on procedural shapes",
      "methods": ["identity", "icp"],
      "experiments": [
        {"id": "mine_partial", "group": "partial", "protocol": "partial", "split": "test",
         "dataset": "procedural", "pairs": {"count": 3}},
        {"id": "mine_jitter", "group": "jitter", "protocol": "jitter", "split": "test",
         "dataset": "procedural", "pairs": {"scale": 0.2}, "comment": "2 pairs of --pairs 10"}
      ]
    })";
    ReproduceOptions o;
    o.experiment_files = {Path("mine.json")};
    o.out_dir = Path("out");
    o.pairs = 10;
    o.timeout_seconds = 0.0;
    o.progress = false;
    std::ostringstream log;
    const ReproduceSummary s = Reproduce(o, log);
    EXPECT_EQ(s.experiments, 2u);
    EXPECT_EQ(s.pairs_generated, 2u);
    EXPECT_EQ(s.rows_run, 2u * 3 + 2u * 2) << log.str();
    EXPECT_EQ(ReadJsonl(Path("out/results/mine_partial.jsonl")).size(), 6u);
    EXPECT_EQ(ReadJsonl(Path("out/results/mine_jitter.jsonl")).size(), 4u);
    std::ifstream in(s.markdown_path);
    const std::string md((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(md.find("My table"), std::string::npos) << md;
    EXPECT_NE(md.find("Two methods on procedural shapes. Ours: partial: dataset `procedural`"),
              std::string::npos)
        << md;
    EXPECT_NE(md.find("| method | MAE(R) partial | MAE(t) partial | CCD partial | MAE(R) jitter"),
              std::string::npos)
        << md;
    // A table the paper lacks has no paper side.
    EXPECT_EQ(md.find("paper MAE"), std::string::npos) << md;
    EXPECT_EQ(md.find("Paper:"), std::string::npos) << md;
    EXPECT_TRUE(std::filesystem::exists(s.html_path));

    const ReproduceSummary again = Reproduce(o, log);  // resumes: nothing left to do
    EXPECT_EQ(again.pairs_generated, 0u);
    EXPECT_EQ(again.rows_run, 0u);
}

TEST_F(UserExperiment, TimingVariantsRunOnTheTimedPairsAsTheirOwnRows) {
    // As Tab. 6's OGMM_full_attention (ogmm with {"attention": "full"}), with a classical
    // method: icp with one iteration is a row of its own; a variant whose method does not run
    // in this invocation is left out.
    std::ofstream(Path("timing.json")) << R"({
      "table": "my_timing", "title": "My timing", "methods": ["identity", "icp"],
      "experiments": [{"id": "timed", "protocol": "partial", "split": "test",
                       "dataset": "procedural", "pairs": {"count": 2}}],
      "timing_of": "timed",
      "timing_variants": [{"row": "icp_one_step", "method": "icp",
                           "params": {"max_iterations": 1}},
                          {"row": "cpd_row", "method": "cpd"}]
    })";
    ReproduceOptions o;
    o.experiment_files = {Path("timing.json")};
    o.out_dir = Path("out");
    o.timeout_seconds = 0.0;
    o.progress = false;
    std::ostringstream log;
    const ReproduceSummary s = Reproduce(o, log);
    EXPECT_EQ(s.rows_run, 2u * 2 + 2u) << log.str();
    const auto rows = ReadJsonl(Path("out/results/timing_icp_one_step.jsonl"));
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows[0]["method"], "icp");
    EXPECT_EQ(rows[0]["params"]["max_iterations"], 1);
    EXPECT_NE(log.str().find("cpd does not run, so row cpd_row is not run"), std::string::npos)
        << log.str();
    std::ifstream in(s.markdown_path);
    const std::string md((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(md.find("| icp_one_step |"), std::string::npos) << md;
    EXPECT_NE(md.find("| icp |"), std::string::npos) << md;
    EXPECT_EQ(md.find("cpd_row"), std::string::npos) << md;
}

TEST_F(UserExperiment, UnknownTableOfTheFilesIsRefused) {
    std::ofstream(Path("mine.json"))
        << R"({"table": "mine", "title": "t", "experiments": [{"id": "a", "protocol": "partial",
              "split": "test", "dataset": "procedural"}]})";
    ReproduceOptions o;
    o.experiment_files = {Path("mine.json")};
    o.out_dir = Path("out");
    o.tables = {"table1"};
    std::ostringstream log;
    try {
        (void)Reproduce(o, log);
        ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(), "--tables: 'table1' names no table (mine)");
    }
}

}  // namespace
}  // namespace regbench
