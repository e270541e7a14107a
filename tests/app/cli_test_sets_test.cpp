// The CLI's test sets as the authors evaluate them: `generate --pairs all` and `reproduce` on a
// tiny ICL-NUIM test file (pairing `stored`). Expected values come from the files the tests
// write themselves (the stored clouds round-trip unchanged) and from counting items by hand.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "protocols/pair_file.hpp"
#include "tests/testing/cli.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;

using testing::CliResult;
using testing::RunCli;

fs::path FreshDir(const std::string& name) {
    const fs::path dir = regbench::testing::TempPath("cli_sets_" + name);
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

/// n points of a 3D grid with spacing 0.1 written as `x y z` lines.
void WriteXyz(const fs::path& path, int n, double offset) {
    std::ofstream f(path);
    for (int i = 0; i < n; ++i) {
        f << offset + 0.1 * (i % 7) << " " << 0.1 * ((i / 7) % 7) << " " << 0.1 * (i / 49) << "\n";
    }
}

/// One float dataset of the given shape in an open HDF5 file.
void WriteDataset(hid_t file, const char* name, const std::vector<hsize_t>& dims,
                  const std::vector<double>& values, hid_t type) {
    const hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
    const hid_t ds = H5Dcreate2(file, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
    H5Dclose(ds);
    H5Sclose(space);
}

/// A DeepGMR-layout stored-pair file's arrays: `count` pairs of `points` points each (p_i =
/// (0.125 i, 0.25 (i % 2) + s, 0.5 (i % 3)) in pair s), each target the source translated by
/// `step * s` along `axis`, the transform that translation (so target = T source exactly).
struct StoredPairs {
    hsize_t count, points;
    std::vector<double> source, target, transform;
};

StoredPairs TranslatedPairs(int count, int points, int axis, double step) {
    StoredPairs sp{static_cast<hsize_t>(count), static_cast<hsize_t>(points), {}, {}, {}};
    for (int s = 0; s < count; ++s) {
        for (int i = 0; i < points; ++i) {
            const std::vector<double> p = {0.125 * i, 0.25 * (i % 2) + s, 0.5 * (i % 3)};
            sp.source.insert(sp.source.end(), p.begin(), p.end());
            std::vector<double> q = p;
            q[static_cast<std::size_t>(axis)] += step * s;
            sp.target.insert(sp.target.end(), q.begin(), q.end());
        }
        std::vector<double> T = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        T[static_cast<std::size_t>(axis) * 4 + 3] = step * s;
        sp.transform.insert(sp.transform.end(), T.begin(), T.end());
    }
    return sp;
}

/// Writes `sp` as datasets source / target (float32) and transform (of `transform_type`).
void WriteStoredPairs(const fs::path& path, const StoredPairs& sp, hid_t transform_type) {
    const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    WriteDataset(file, "source", {sp.count, sp.points, 3}, sp.source, H5T_IEEE_F32LE);
    WriteDataset(file, "target", {sp.count, sp.points, 3}, sp.target, H5T_IEEE_F32LE);
    WriteDataset(file, "transform", {sp.count, 4, 4}, sp.transform, transform_type);
    H5Fclose(file);
}

/// Pair k of `set` must be stored pair k % count exactly: float32 points widened, the
/// translation as stored.
void ExpectStoredPairs(const PairSet& set, const StoredPairs& sp) {
    for (std::size_t k = 0; k < set.pairs.size(); ++k) {
        const std::size_t s = k % sp.count;
        ASSERT_EQ(set.pairs[k].source.rows(), static_cast<Eigen::Index>(sp.points));
        for (std::size_t d = 0; d < 3; ++d) {
            const auto col = static_cast<Eigen::Index>(d);
            EXPECT_EQ(set.pairs[k].T_gt(col, 3), sp.transform[s * 16 + d * 4 + 3]);
            for (std::size_t i = 0; i < sp.points; ++i) {
                const std::size_t at = (s * sp.points + i) * 3 + d;
                const auto row = static_cast<Eigen::Index>(i);
                EXPECT_EQ(set.pairs[k].source(row, col), sp.source[at]);
                EXPECT_EQ(set.pairs[k].target(row, col), sp.target[at]);
            }
        }
    }
}

TEST(CliTestSets, PairsAllMakesOnePairPerItem) {
    // A folder of 3 point files is a dataset of 3 items (split `all`).
    const fs::path dir = FreshDir("pairs_all");
    fs::create_directories(dir / "clouds");
    for (int k = 0; k < 3; ++k)
        WriteXyz(dir / "clouds" / ("c" + std::to_string(k) + ".xyz"), 60, k);
    const std::string out = (dir / "all.h5").string();
    const CliResult r =
        RunCli("generate --protocol partial --dataset " + (dir / "clouds").string() +
               " --points 50 --pairs all --seed 1 --out " + out);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const PairSet set = ReadPairFile(out);
    ASSERT_EQ(set.pairs.size(), 3u);
    EXPECT_EQ(set.provenance.at("pair_selection"), "one-per-item");
    EXPECT_NE(set.pairs[0].shape, set.pairs[1].shape);
    EXPECT_NE(set.pairs[1].shape, set.pairs[2].shape);
    EXPECT_NE(set.pairs[0].shape, set.pairs[2].shape);
    // Anything but a whole number or `all` is refused, naming the option, with no file left.
    const std::string bad = (dir / "bad.h5").string();
    const CliResult refused = RunCli("generate --protocol partial --dataset " +
                                     (dir / "clouds").string() + " --pairs every --out " + bad);
    EXPECT_GT(refused.exit_code, 0);
    EXPECT_NE(refused.output.find("--pairs"), std::string::npos) << refused.output;
    EXPECT_FALSE(fs::exists(bad));
    fs::remove_all(dir);
}

TEST(CliTestSets, ReproduceUsesTheStoredIclNuimPairs) {
    const fs::path dir = FreshDir("reproduce_icl");
    // ICL-NUIM root: test/icl_nuim.h5 with 2 stored pairs of 6 points; the transform is a
    // translation by (0.5 s, 0, 0) with the identity rotation, so target = source + t is exact.
    const StoredPairs stored = TranslatedPairs(2, 6, 0, 0.5);
    fs::create_directories(dir / "icl" / "test");
    WriteStoredPairs(dir / "icl" / "test" / "icl_nuim.h5", stored, H5T_IEEE_F64LE);
    // 7Scenes root with one test (office) scan of 2100 points (the protocol samples 2048).
    fs::create_directories(dir / "7s" / "7-scenes-office");
    {
        std::ofstream ply(dir / "7s" / "7-scenes-office" / "frame0.ply");
        ply << "ply\nformat ascii 1.0\nelement vertex 2100\nproperty float x\nproperty float y\n"
               "property float z\nend_header\n";
        for (int i = 0; i < 2100; ++i) {
            ply << 0.05 * (i % 30) << " " << 0.05 * ((i / 30) % 10) << " " << 0.05 * (i / 300)
                << "\n";
        }
    }
    const fs::path out = dir / "report";
    const CliResult r = RunCli(
        "reproduce --tables table3 --methods identity --pairs 4 --jobs 1 "
        "--icl-nuim " +
        (dir / "icl").string() + " --7scenes " + (dir / "7s").string() + " --out " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("report folder: " + out.string()), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("HTML report:   " + (out / "report.html").string()), std::string::npos)
        << r.output;
    EXPECT_TRUE(fs::exists(out / "report.html"));
    // --pairs 4 on --tables table3 gives max(4, 4 / 2) = 4 indoor pairs: the 2 stored pairs,
    // cycled. Each is exactly the file's (float32 values widened; the transform as stored).
    const PairSet set = ReadPairFile((out / "pairs" / "tab3_icl_nuim.h5").string());
    EXPECT_EQ(set.provenance.at("pairing"), "stored");
    ASSERT_EQ(set.pairs.size(), 4u);
    ExpectStoredPairs(set, stored);
    // 7Scenes keeps the resampling protocol.
    EXPECT_EQ(ReadPairFile((out / "pairs" / "tab3_7scenes.h5").string()).provenance.at("pairing"),
              "independent");
    // The table says which pairing each column used and prints both floors. The stored pairs
    // are exact (target = T source), so the icl_nuim floor is 0.
    std::ifstream md(out / "tables.md");
    const std::string tables((std::istreambuf_iterator<char>(md)),
                             std::istreambuf_iterator<char>());
    EXPECT_NE(tables.find("pairing stored"), std::string::npos);
    EXPECT_NE(tables.find("Ground-truth CCD floor (icl_nuim): 0.0000"), std::string::npos)
        << tables;
    EXPECT_NE(tables.find("Ground-truth CCD floor (7scenes)"), std::string::npos);
    fs::remove_all(dir);
}

// A DeepGMR test file given as the dataset (any name; detected by its source / target /
// transform datasets): `generate --pairing stored --pairs all` needs no --split, uses each pair
// as stored, and the pair file and the report caption carry the file's sha256 (expected value:
// coreutils' sha256sum of the same file).
TEST(CliTestSets, DeepGmrTestFileByItselfGivesItsStoredPairsAndHash) {
    const fs::path dir = FreshDir("deepgmr_file");
    const StoredPairs stored = TranslatedPairs(3, 8, 1, 0.25);
    const fs::path h5 = dir / "my_copy_of_the_clean_set.h5";
    WriteStoredPairs(h5, stored, H5T_IEEE_F32LE);
    const fs::path pairs = dir / "pairs.h5";
    const CliResult g = RunCli("generate --dataset " + h5.string() +
                               " --pairing stored --pairs all --points 8 --out " + pairs.string());
    ASSERT_EQ(g.exit_code, 0) << g.output;
    const PairSet set = ReadPairFile(pairs.string());
    ASSERT_EQ(set.pairs.size(), 3u);
    ExpectStoredPairs(set, stored);
    FILE* p = ::popen(("sha256sum " + h5.string()).c_str(), "r");
    ASSERT_NE(p, nullptr);
    char buf[65] = {0};
    ASSERT_EQ(std::fread(buf, 1, 64, p), 64u);
    ::pclose(p);
    EXPECT_EQ(set.provenance.at("dataset_sha256"), std::string(buf));
    const fs::path rows = dir / "rows.jsonl";
    ASSERT_EQ(
        RunCli("run --pairs " + pairs.string() + " --methods identity -q --out " + rows.string())
            .exit_code,
        0);
    const CliResult rep = RunCli("report " + rows.string());
    ASSERT_EQ(rep.exit_code, 0) << rep.output;
    EXPECT_NE(rep.output.find("dataset `" + h5.string() + "` (sha256 " + std::string(buf) + ")"),
              std::string::npos)
        << rep.output;
    fs::remove_all(dir);
}

/// What ReproduceWithOneVariant leaves: its folder, the report folder in it, tables.json and
/// whether this build has ogmm.
struct VariantRun {
    fs::path dir, out;
    nlohmann::json cells;
    bool learned = false;
};

/// `regbench reproduce ARGS --jobs 1 --out DIR/report` in a fresh folder DIR (FreshDir(name))
/// with $REGBENCH_MODELS = DIR/models holding the shipped ogmm checkpoint as `ogmm` and as the
/// one variant ablation/KIND/ROW (any OGMM checkpoint will do: a variant is named by its
/// folder).
void ReproduceWithOneVariant(const std::string& name, const std::string& kind,
                             const std::string& row, const std::string& args, VariantRun* v) {
    v->dir = FreshDir(name);
    v->out = v->dir / "report";
    const fs::path& dir = v->dir;
    const char* src_env = std::getenv("REGBENCH_SOURCE_DIR");
    ASSERT_NE(src_env, nullptr) << "CTest sets REGBENCH_SOURCE_DIR";
    const fs::path shipped = fs::path(src_env) / "data" / "models" / "ogmm";
    ASSERT_TRUE(fs::exists(shipped / "checkpoint.json")) << shipped;
    fs::create_directories(dir / "models" / "ablation" / kind);
    fs::create_directory_symlink(shipped, dir / "models" / "ogmm");
    fs::create_directory_symlink(shipped, dir / "models" / "ablation" / kind / row);
    v->learned = RunCli("methods").output.find("ogmm") != std::string::npos;
    ::setenv("REGBENCH_MODELS", (dir / "models").c_str(), 1);
    const CliResult r = RunCli("reproduce " + args + " --jobs 1 --out " + v->out.string());
    ::unsetenv("REGBENCH_MODELS");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::ifstream f(v->out / "tables.json");
    v->cells = nlohmann::json::parse(f);
}

TEST(CliTestSets, ReproduceFillsAblationRowsFromShippedVariantCheckpoints) {
    // Tab. 4 rows come from checkpoints under $REGBENCH_MODELS/ablation/components/<paper row>.
    // Here only no_SPE has one (any OGMM checkpoint will do: the row is named by its folder),
    // so no_SPE is measured on the Tab. 1 same-category pairs and the other rows say
    // "not trained". A build without LibTorch has no ogmm: every row says "not trained".
    VariantRun v;
    ASSERT_NO_FATAL_FAILURE(
        ReproduceWithOneVariant("reproduce_ablation", "components", "no_SPE",
                                "--tables table4 --methods identity,ogmm --pairs 2", &v));
    const bool learned = v.learned;
    int measured_no_spe = 0, not_trained = 0;
    for (const auto& c : v.cells) {
        if (c.at("table") != "table4_ablation_components") continue;
        if (c.at("source") != "measured") continue;
        if (c.at("row") == "no_SPE" && learned) {
            EXPECT_TRUE(c.at("value").is_number()) << c.dump();
            EXPECT_EQ(c.at("pairs"), 2) << c.dump();
            EXPECT_EQ(c.at("pairs_file"), "tab1_same.h5") << c.dump();
            ++measured_no_spe;
        } else {
            EXPECT_EQ(c.at("text"), "not trained") << c.dump();
            ++not_trained;
        }
    }
    // 3 metrics per row: no_SPE measured, the other three rows (all four without LibTorch) not.
    EXPECT_EQ(measured_no_spe, learned ? 3 : 0);
    EXPECT_EQ(not_trained, learned ? 9 : 12);
    if (learned) {
        EXPECT_TRUE(fs::exists(v.out / "results" / "ablation_components_no_SPE.jsonl"));
        EXPECT_FALSE(fs::exists(v.out / "results" / "ablation_components_full.jsonl"));
    }
    fs::remove_all(v.dir);
}

TEST(CliTestSets, ReproduceFillsClusterCountColumnsFromVariantCheckpoints) {
    // The cluster-count table's columns are J: 32 is the shipped ogmm (ogmm-small has J = 32),
    // the others variants under $REGBENCH_MODELS/ablation/clusters/<J>. Here only J = 8 has one
    // (any OGMM checkpoint will do), so OGMM's row has columns 32 and 8 measured on the sweep's
    // 50% level and '-' in 16, 48 and 64. Without LibTorch nothing is measured.
    VariantRun v;
    ASSERT_NO_FATAL_FAILURE(ReproduceWithOneVariant("reproduce_clusters", "clusters", "8",
                                                    "--tables supp_cluster --pairs 2", &v));
    const bool learned = v.learned;
    std::set<std::string> measured;
    for (const auto& c : v.cells) {
        if (c.at("table") != "supp_cluster_count" || c.at("source") != "measured") continue;
        if (!c.at("value").is_number()) continue;
        EXPECT_EQ(c.at("row"), "OGMM") << c.dump();
        EXPECT_EQ(c.at("pairs"), 2) << c.dump();
        EXPECT_EQ(c.at("pairs_file"), "supp_clusters.h5") << c.dump();
        const std::string column = c.at("column");  // "<J>.<metric>"
        measured.insert(column.substr(0, column.find('.')));
    }
    EXPECT_EQ(measured, learned ? (std::set<std::string>{"32", "8"}) : std::set<std::string>{});
    if (learned) {
        EXPECT_TRUE(fs::exists(v.out / "results" / "ablation_clusters_8.jsonl"));
    } else {
        // Without LibTorch the table is still written, saying why it is empty.
        std::ifstream md(v.out / "tables.md");
        const std::string text{std::istreambuf_iterator<char>(md), {}};
        EXPECT_NE(text.find("No regbench run fills this table"), std::string::npos) << text;
    }
    fs::remove_all(v.dir);
}

}  // namespace
}  // namespace regbench
