// `generate` end to end through the real dataset loader (DatasetShapeLoader): the procedural
// corpus needs no data files.
#include "datasets/dataset_shapes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "protocols/generate.hpp"
#include "protocols/pair_file.hpp"
#include "tests/datasets/test_files.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

std::string FreshDir(const std::string& name) {
    const auto dir = regbench::testing::TempPath("test_" + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir.string();
}

GenerateRequest Request(const std::string& out, const std::string& dataset) {
    GenerateRequest r;
    r.dataset = dataset;
    r.split = "test";
    r.num_pairs = 4;
    r.seed = 9;
    r.out = out;
    return r;
}

TEST(DatasetShapeLoader, ProceduralDatasetThroughGenerate) {
    // Shapes load once, pairs come out with the protocol's point count (717 = 70% of 1024).
    const std::string dir = FreshDir("generate_procedural");
    GenerateToFile(Request(dir + "/p.h5", "procedural"), DatasetShapeLoader(DatasetOptions{}));
    const PairSet set = ReadPairFile(dir + "/p.h5");
    ASSERT_EQ(set.pairs.size(), 4u);
    EXPECT_EQ(set.pairs[0].source.rows(), 717);
    EXPECT_FALSE(set.pairs[0].shape.empty());
    std::filesystem::remove_all(dir);
}

TEST(DatasetShapeLoader, MissingDatasetPathFailsAndLeavesNoFile) {
    const std::string dir = FreshDir("generate_missing_dataset");
    const std::string out = dir + "/p.h5";
    try {
        GenerateToFile(Request(out, dir + "/no_such_dataset"),
                       DatasetShapeLoader(DatasetOptions{}));
        ADD_FAILURE() << "missing dataset path accepted";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("no_such_dataset"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(out));
    std::filesystem::remove_all(dir);
}

TEST(DatasetShapeLoader, IclNuimTestFileGivesItsStoredPairsUnderPairingStored) {
    // A tiny ICL-NUIM root in DeepGMR's layout: test/icl_nuim.h5 with source, target [2, 5, 3]
    // (float32) and transform [2, 4, 4] (float64). Pair s must come back as stored: the same
    // float32 values widened to double, and the transform (a rotation of 90 degrees about z,
    // written out by hand, plus t = (s, 0, 0)) unchanged.
    const std::filesystem::path root = FreshDir("icl_stored");
    std::vector<double> source, target;
    for (int i = 0; i < 2 * 5 * 3; ++i) {
        source.push_back(0.25 * i);  // exact in float32
        target.push_back(-0.5 * i);  // need not equal T * source: stored pairs are used as is
    }
    std::vector<double> transform;
    for (int s = 0; s < 2; ++s) {
        const std::vector<double> T = {0, -1, 0, double(s), 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        transform.insert(transform.end(), T.begin(), T.end());
    }
    testing::WriteH5(root / "test" / "icl_nuim.h5",
                     {{"source", {2, 5, 3}, source},
                      {"target", {2, 5, 3}, target},
                      {"transform", {2, 4, 4}, transform, H5T_IEEE_F64LE}});
    GenerateRequest r = Request((root / "stored.h5").string(), root.string());
    r.one_per_item = true;
    r.options = DefaultProtocolOptions(Protocol::kIndoor);
    r.options.pairing = Pairing::kStored;
    GenerateToFile(r, DatasetShapeLoader(DatasetOptions{}));
    const PairSet set = ReadPairFile(r.out);
    ASSERT_EQ(set.pairs.size(), 2u);  // one per stored pair
    for (int s = 0; s < 2; ++s) {
        const Pair& p = set.pairs[static_cast<std::size_t>(s)];
        ASSERT_EQ(p.source.rows(), 5);
        for (int i = 0; i < 5; ++i) {
            for (int d = 0; d < 3; ++d) {
                const int k = s * 15 + i * 3 + d;
                EXPECT_EQ(p.source(i, d), 0.25 * k);
                EXPECT_EQ(p.target(i, d), -0.5 * k);
            }
        }
        EXPECT_EQ(p.T_gt(0, 1), -1.0);
        EXPECT_EQ(p.T_gt(1, 0), 1.0);
        EXPECT_EQ(p.T_gt(0, 3), double(s));
    }
    EXPECT_EQ(set.provenance.at("pairing"), "stored");
    EXPECT_EQ(set.provenance.at("pair_selection"), "one-per-item");
    EXPECT_EQ(set.provenance.at("noise_sigma"), 0.0);
    // The default pairing resamples the source cloud instead: every source point is one of
    // the item's stored source points (in a random order), and the file says "independent".
    r.options.pairing = Pairing::kIndependent;
    r.options.points = 5;
    r.options.keep = 1.0;
    r.out = (root / "resampled.h5").string();
    GenerateToFile(r, DatasetShapeLoader(DatasetOptions{}));
    const PairSet resampled = ReadPairFile(r.out);
    EXPECT_EQ(resampled.provenance.at("pairing"), "independent");
    for (int i = 0; i < 5; ++i) {
        const double x = resampled.pairs[1].source(i, 0);  // item 1: x = 0.25 * (15 + 3 j)
        const double j = (x / 0.25 - 15.0) / 3.0;
        EXPECT_EQ(j, std::round(j)) << x;
        EXPECT_GE(j, 0.0);
        EXPECT_LE(j, 4.0);
    }
    std::filesystem::remove_all(root);
}

}  // namespace
}  // namespace regbench
