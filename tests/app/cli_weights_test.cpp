// Issue 56: `reproduce --weights FILE` runs the weights a researcher has, table by table. The
// example manifest of the authors' released files (docs/weights-authors.json) runs on stand-ins
// of those files: each is a .pth in its family's authors' layout, written by
// `export-checkpoint` from a regbench checkpoint (the shipped ones; for DeepGMR, whose shipped
// model is the OGMM paper's variant, a one-step `deepgmr-orig`). Built only with LibTorch
// (tests/CMakeLists.txt).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tests/datasets/test_files.hpp"
#include "tests/testing/cli.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::H5Dataset;
using testing::RunCli;
using testing::RunCliOk;

fs::path Source() {
    const char* src = std::getenv("REGBENCH_SOURCE_DIR");
    return src != nullptr ? fs::path(src) : fs::path(".");
}

std::string Read(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// The rows of every results/*.jsonl of a reproduce folder, as (experiment, method) -> extra.
std::map<std::pair<std::string, std::string>, nlohmann::json> RowExtras(const fs::path& out) {
    std::map<std::pair<std::string, std::string>, nlohmann::json> rows;
    for (const auto& f : fs::directory_iterator(out / "results")) {
        std::ifstream in(f.path());
        std::string line;
        while (std::getline(in, line)) {
            const auto j = nlohmann::json::parse(line, nullptr, false);
            if (j.is_discarded() || !j.contains("method")) continue;
            rows[{f.path().stem().string(), j["method"].get<std::string>()}] =
                j.value("extra", nlohmann::json::object());
        }
    }
    return rows;
}

class CliWeights : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        dir_ = new fs::path(testing::FreshTempDir("cli_weights"));
        // One stand-in per family, in the authors' layout.
        const fs::path models = Source() / "data" / "models";
        RunCliOk("train --model deepgmr-orig --out " + (*dir_ / "dg").string() +
                 " --max-steps 1 --batch 2 --val-pairs 2 --no-val-icp --threads 1 --data-dir " +
                 (Source() / "data").string());
        const std::map<std::string, fs::path> from = {{"deepgmr", *dir_ / "dg" / "last"},
                                                      {"ogmm", models / "ogmm"},
                                                      {"rienet", models / "rienet"},
                                                      {"omnet", models / "omnet"},
                                                      {"rgm", models / "rgm"},
                                                      {"regtr", models / "regtr"}};
        for (const auto& [family, ck] : from) {
            RunCliOk("export-checkpoint " + ck.string() + " --to " + family + " --out " +
                     (*dir_ / (family + ".pth")).string());
        }
        // The docs' manifest beside stand-ins at every path it names. The OGMM stand-in is an
        // ogmm-small (J 32, 32 anchors), which its entries say as a user would for such a file;
        // everything else is the docs' file as it is.
        const fs::path manifest = *dir_ / "authors" / "weights-authors.json";
        fs::create_directories(manifest.parent_path());
        nlohmann::json m = nlohmann::json::parse(Read(Source() / "docs" / "weights-authors.json"));
        for (auto& e : m.at("entries")) {
            const std::string family = e.at("from");
            if (family == "ogmm") e["settings"] = {{"clusters", 32}, {"anchors", 32}};
            const fs::path file = manifest.parent_path() / e.at("authors_file").get<std::string>();
            fs::create_directories(file.parent_path());
            if (!fs::exists(file)) fs::copy_file(*dir_ / (family + ".pth"), file);
        }
        std::ofstream(manifest) << m.dump(1);
    }
    static void TearDownTestSuite() {
        delete dir_;
        dir_ = nullptr;
    }
    /// reproduce --quick of `tables` with `methods` (default: Tab. 1-2 with the six learned
    /// methods).
    static std::string Reproduce(const fs::path& out, const std::string& weights,
                                 const std::string& tables = "table1,table2",
                                 const std::string& methods =
                                     "ogmm,deepgmr,omnet,rienet,rgm,"
                                     "regtr") {
        return "reproduce --quick --pairs 2 --jobs 2 --tables " + tables + " --methods " + methods +
               " --data-dir " + (Source() / "data").string() + " --out " + out.string() +
               (weights.empty() ? "" : " --weights " + weights);
    }
    static inline fs::path* dir_ = nullptr;
};

// Acceptance: Tab. 1-3 filled from the authors' (stand-in) files, imported once into the report
// folder with their presets, named in every caption and row; a second invocation with the same
// manifest continues (nothing re-run), a changed one is refused naming the difference. Tab. 3
// runs the methods the manifest names there (OMNet's, RGM's and REGTR's authors trained no
// indoor model, and they are the slowest on the 2048-point scans), in a second invocation on
// the same folder.
TEST_F(CliWeights, AuthorsFilesFillTables1To3AndAreNamedInCaptionsAndRows) {
    const fs::path manifest = *dir_ / "authors" / "weights-authors.json";
    const fs::path out = *dir_ / "out";
    const CliResult r = RunCli(Reproduce(out, manifest.string()));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string tables12 = Read(out / "tables.md");  // each invocation writes its tables
    const std::string csv12 = Read(out / "tables.csv");
    const CliResult r3 = RunCli(Reproduce(out, manifest.string(), "table3", "ogmm,deepgmr,rienet"));
    ASSERT_EQ(r3.exit_code, 0) << r3.output;
    // Every learned row of Tab. 1-3 ran imported weights, with their label and sha256.
    const auto rows = RowExtras(out);
    std::set<std::string> experiments;
    for (const auto& [key, extra] : rows) {
        if (key.second == "identity") continue;
        SCOPED_TRACE(key.first + " " + key.second);
        experiments.insert(key.first);
        EXPECT_EQ(extra.value("checkpoint_source", ""), "authors");
        EXPECT_EQ(extra.value("checkpoint_sha256", "").size(), 64u);
        EXPECT_NE(extra.value("checkpoint_label", "").find("imported"), std::string::npos);
    }
    EXPECT_EQ(experiments,
              (std::set<std::string>{"tab1_same", "tab1_cross", "tab2_jitter", "tab2_density",
                                     "tab3_7scenes", "tab3_icl_nuim"}));
    // RIENet's 7Scenes file ran with the authors' 7Scenes config (no tensor holds it).
    const std::string rienet7 = rows.at({"tab3_7scenes", "rienet"}).at("checkpoint");
    const auto config = nlohmann::json::parse(Read(fs::path(rienet7) / "checkpoint.json"));
    EXPECT_EQ(config.at("config").at("k"), 8);
    EXPECT_EQ(config.at("config").at("k_nc"), 8);
    EXPECT_EQ(config.at("config").at("nn_margin"), 0.5);
    EXPECT_EQ(config.at("config").at("keypoints"), 768);
    EXPECT_EQ(fs::path(rienet7).parent_path(), out / "weights");
    // The captions name the weights of every cell.
    const std::string tables3 = Read(out / "tables.md");
    for (const char* label : {"rienet = rienet-7scenes: model rienet-authors, imported (preset "
                              "7scenes) (authors, sha256 ",
                              "ogmm = ogmm-icl_nuim: model ogmm-authors, imported (authors, "}) {
        EXPECT_NE(tables3.find(label), std::string::npos) << label;
    }
    for (const char* label : {"deepgmr = deepgmr-modelnet_clean: model deepgmr-orig, imported",
                              "rienet = rienet-modelnet-unseen: model rienet, imported (preset "
                              "modelnet40)",
                              "regtr = regtr-modelnet: model regtr, imported (authors, sha256 "}) {
        EXPECT_NE(tables12.find(label), std::string::npos) << label;
    }
    EXPECT_NE(csv12.find("rgm = rgm-modelnet: model rgm, imported"), std::string::npos);
    // Resumed with the same manifest: nothing runs again.
    const CliResult again = RunCli(Reproduce(out, manifest.string()));
    ASSERT_EQ(again.exit_code, 0) << again.output;
    EXPECT_NE(again.output.find("0 calls run"), std::string::npos) << again.output;
    // Another manifest (the shipped one) on the same folder: refused, nothing changed.
    const std::string before = Read(out / "weights.json");
    const CliResult other = RunCli(Reproduce(out, ""));
    EXPECT_NE(other.exit_code, 0);
    EXPECT_NE(other.output.find("was run with other weights"), std::string::npos) << other.output;
    EXPECT_EQ(Read(out / "weights.json"), before);
}

// Every way a manifest can fail to fit the plan is refused before any work, naming the entry
// (exit 1, as every refused input file), and no pair file generated.
TEST_F(CliWeights, ManifestsThatDoNotFitAreRefusedBeforeAnyWork) {
    const fs::path ogmm = Source() / "data" / "models" / "ogmm";
    const std::string rgm = (*dir_ / "rgm.pth").string();
    const std::map<std::string, std::pair<nlohmann::json, std::string>> cases = {
        {"experiment",
         {{{"experiments", {"tab9_moon"}}, {"methods", {"ogmm"}}, {"checkpoint", ogmm}},
          "names experiment 'tab9_moon'"}},
        {"classical",
         {{{"experiments", {"tab1_same"}}, {"methods", {"icp"}}, {"checkpoint", ogmm}},
          "'icp', which is not a learned method"}},
        {"not run",
         {{{"experiments", {"supp_clusters"}},
           {"methods", {"rgm"}},
           {"authors_file", rgm},
           {"from", "rgm"}},
          "does not run it"}},
        {"missing folder",
         {{{"experiments", {"tab1_same"}}, {"methods", {"ogmm"}}, {"checkpoint", "no/such"}},
          "is not a regbench checkpoint folder"}},
        {"missing file",
         {{{"experiments", {"tab1_same"}},
           {"methods", {"rgm"}},
           {"authors_file", "none.pth"},
           {"from", "rgm"}},
          "none.pth: no such file"}},
        {"format",
         {{{"experiments", {"tab1_same"}},
           {"methods", {"rgm"}},
           {"authors_file", rgm},
           {"from", "pointnetlk"}},
          "'pointnetlk' is no authors' format"}},
        {"preset",
         {{{"experiments", {"tab3_7scenes"}},
           {"methods", {"rienet"}},
           {"authors_file", rgm},
           {"from", "rienet"},
           {"preset", "scannet"}},
          "unknown preset 'scannet'"}},
        {"both sources",
         {{{"experiments", {"tab1_same"}},
           {"methods", {"ogmm"}},
           {"checkpoint", ogmm},
           {"authors_file", rgm}},
          "needs exactly one of"}}};
    for (const auto& [name, c] : cases) {
        SCOPED_TRACE(name);
        const fs::path file = *dir_ / "bad.json";
        nlohmann::json m = {{"format", "regbench-weights"}, {"format_version", 1}};
        nlohmann::json e = c.first;
        e["label"] = "entry-" + name;
        m["entries"] = {e};
        std::ofstream(file, std::ios::trunc) << m.dump();
        const fs::path out = *dir_ / "refused";
        const CliResult r = RunCli(Reproduce(out, file.string()));
        EXPECT_EQ(r.exit_code, 1) << r.output;
        EXPECT_NE(r.output.find(c.second), std::string::npos) << r.output;
        EXPECT_NE(r.output.find("entry-" + name), std::string::npos) << r.output;  // the entry
        EXPECT_FALSE(fs::exists(out / "pairs")) << r.output;
    }
}

/// n points on a bumpy sphere of radius ~0.5 (item `item`: its own bumps), flattened xyz.
std::vector<double> BumpySphere(int n, int item) {
    std::vector<double> xyz;
    for (int i = 0; i < n; ++i) {
        const double z = 1.0 - 2.0 * (i + 0.5) / n;
        const double phi = 2.399963 * i;  // golden angle: an even spread
        const double r = std::sqrt(1.0 - z * z);
        const double bump = 0.5 + 0.08 * std::sin(3.0 * phi + item) * std::cos(5.0 * z + item);
        xyz.insert(xyz.end(), {bump * r * std::cos(phi), bump * r * std::sin(phi), bump * z});
    }
    return xyz;
}

// Issue 56 item 4: a run on real data in one command. Miniature datasets in the real layouts
// (ModelNet40's HDF5 release, a 7Scenes scan folder, ICL-NUIM's stored-pair test file) and a
// manifest with the authors' (stand-in) RIENet files under their presets: Tab. 1 and 3 run from
// the real data and those files, and every caption names both (no fallback note).
TEST_F(CliWeights, RealLayoutDatasetsAndAuthorsWeightsInOneCommand) {
    const fs::path data = *dir_ / "real";
    const fs::path mn = data / "modelnet40_ply_hdf5_2048";
    const hsize_t p = 2048;
    std::vector<double> train, test;
    for (int i = 0; i < 4; ++i) {
        for (const double v : BumpySphere(static_cast<int>(p), i)) train.push_back(v);
        for (const double v : BumpySphere(static_cast<int>(p), 10 + i)) test.push_back(v);
    }
    // Labels 0 and 1 (same-category split, categories 0-19), 25 and 30 (cross, 20-39).
    testing::WriteH5(mn / "ply_data_train0.h5",
                     {{"data", {4, p, 3}, train}, {"label", {4, 1}, {0, 1, 25, 30}, H5T_STD_U8LE}});
    testing::WriteH5(mn / "ply_data_test0.h5",
                     {{"data", {4, p, 3}, test}, {"label", {4, 1}, {0, 1, 25, 30}, H5T_STD_U8LE}});
    std::string names;
    for (int c = 0; c < 40; ++c) names += "class" + std::to_string(c) + "\n";
    testing::WriteText(mn / "shape_names.txt", names);
    // 7Scenes: one test (office) scan of 2100 points; ICL-NUIM: 2 stored pairs of 300 points.
    {
        fs::create_directories(data / "7s" / "7-scenes-office");
        std::ofstream ply(data / "7s" / "7-scenes-office" / "frame0.ply");
        ply << "ply\nformat ascii 1.0\nelement vertex 2100\nproperty float x\nproperty float "
               "y\nproperty float z\nend_header\n";
        const std::vector<double> scan = BumpySphere(2100, 3);
        for (std::size_t i = 0; i < scan.size(); i += 3)
            ply << scan[i] << " " << scan[i + 1] << " " << scan[i + 2] << "\n";
    }
    std::vector<double> src, tgt, transform;
    for (int s = 0; s < 2; ++s) {
        const std::vector<double> pts = BumpySphere(300, 20 + s);
        src.insert(src.end(), pts.begin(), pts.end());
        for (std::size_t i = 0; i < pts.size(); ++i)
            tgt.push_back(pts[i] + (i % 3 == 0 ? 0.1 : 0.0));
        transform.insert(transform.end(), {1, 0, 0, 0.1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
    }
    testing::WriteH5(data / "icl" / "test" / "icl_nuim.h5",
                     {{"source", {2, 300, 3}, src},
                      {"target", {2, 300, 3}, tgt},
                      {"transform", {2, 4, 4}, transform, H5T_IEEE_F64LE}});
    const fs::path manifest = data / "weights.json";
    std::ofstream(manifest) << nlohmann::json{{"format", "regbench-weights"},
                                              {"format_version", 1},
                                              {"entries",
                                               {{{"label", "rienet-modelnet"},
                                                 {"experiments", {"table1_modelnet_partial"}},
                                                 {"methods", {"rienet"}},
                                                 {"authors_file", (*dir_ / "rienet.pth").string()},
                                                 {"from", "rienet"},
                                                 {"preset", "modelnet40"}},
                                                {{"label", "rienet-7scenes"},
                                                 {"experiments", {"tab3_7scenes"}},
                                                 {"methods", {"rienet"}},
                                                 {"authors_file", (*dir_ / "rienet.pth").string()},
                                                 {"from", "rienet"},
                                                 {"preset", "7scenes"}},
                                                {{"label", "rienet-icl_nuim"},
                                                 {"experiments", {"tab3_icl_nuim"}},
                                                 {"methods", {"rienet"}},
                                                 {"authors_file", (*dir_ / "rienet.pth").string()},
                                                 {"from", "rienet"},
                                                 {"preset", "icl_nuim"}}}}}
                                   .dump();
    const fs::path out = *dir_ / "real_out";
    const CliResult r = RunCli(
        "reproduce --tables table1,table3 --methods identity,rienet --pairs 2 --jobs 2 "
        "--modelnet40 " +
        mn.string() + " --7scenes " + (data / "7s").string() + " --icl-nuim " +
        (data / "icl").string() + " --weights " + manifest.string() + " --out " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string tables = Read(out / "tables.md");
    EXPECT_EQ(tables.find("instead of"), std::string::npos) << tables;  // no fallback
    for (const std::string& s :
         {mn.string(), (data / "7s").string(), (data / "icl").string(),
          std::string("rienet = rienet-modelnet: model rienet, imported (preset modelnet40)"),
          std::string("rienet = rienet-7scenes: model rienet-authors, imported (preset 7scenes)"),
          std::string("rienet = rienet-icl_nuim: model rienet-authors, imported (preset "
                      "icl_nuim)")}) {
        EXPECT_NE(tables.find(s), std::string::npos) << s;
    }
    const auto rows = RowExtras(out);
    EXPECT_EQ(rows.at({"tab3_icl_nuim", "rienet"}).value("checkpoint_source", ""), "authors");
}

}  // namespace
}  // namespace regbench
