#include "protocols/generate.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/usage_error.hpp"
#include "protocols/pair_file.hpp"
#include "protocols/pair_summary.hpp"
#include "tests/protocols/test_shapes.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

/// Loader over the in-test shapes; counts calls so tests can prove no work was done.
struct CountingLoader {
    int* calls;
    std::vector<ShapeSource> operator()(const std::string& dataset, const std::string&) const {
        ++*calls;
        if (dataset != "test") throw std::runtime_error("dataset '" + dataset + "': not found");
        return test::TestShapes();
    }
};

GenerateRequest Request(const std::string& out) {
    GenerateRequest r;
    r.dataset = "test";
    r.num_pairs = 4;
    r.seed = 9;
    r.out = out;
    r.extra_provenance = {{"regbench_version", "x"}};
    return r;
}

TEST(Generate, WritesOneFileWithProvenanceAndProgress) {
    const std::string dir = testing::FreshTempDir("generate_ok");
    int calls = 0;
    std::size_t last = 0;
    GenerateToFile(Request(dir + "/p.h5"), CountingLoader{&calls},
                   [&](std::size_t done, std::size_t) { last = done; });
    EXPECT_EQ(calls, 1);
    EXPECT_EQ(last, 4u);
    const PairSet set = ReadPairFile(dir + "/p.h5");
    EXPECT_EQ(set.pairs.size(), 4u);
    EXPECT_EQ(set.provenance.at("dataset"), "test");
    EXPECT_EQ(set.provenance.at("seed"), 9);
    EXPECT_EQ(set.provenance.at("protocol"), "partial");
    EXPECT_EQ(set.provenance.at("regbench_version"), "x");
    EXPECT_FALSE(std::filesystem::exists(dir + "/p.h5.tmp"));
    const PairSetSummary s = SummarizePairSet(set);
    EXPECT_EQ(s.min_source_points, 717);
    EXPECT_LE(s.max_rotation_deg, 45.0 * std::sqrt(3.0));
    EXPECT_GT(s.gt_ccd_mean, 0.0);  // independent samples: no exact correspondences
    EXPECT_LT(s.gt_ccd_mean, 0.2);
    std::filesystem::remove_all(dir);
}

TEST(Generate, BadRequestsFailBeforeWorkAndLeaveNoFile) {
    const std::string dir = testing::FreshTempDir("generate_bad");
    const std::string out = dir + "/p.h5";
    int calls = 0;
    const auto fails = [&](GenerateRequest r, const std::string& needle) {
        try {
            GenerateToFile(r, CountingLoader{&calls});
            ADD_FAILURE() << "no error, expected " << needle;
        } catch (const std::exception& e) {
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
        EXPECT_FALSE(std::filesystem::exists(out));
        EXPECT_FALSE(std::filesystem::exists(out + ".tmp"));
    };
    GenerateRequest r = Request(out);
    r.options.keep = 1.2;
    fails(r, "keep");
    r = Request(out);
    r.options.points = 2;
    fails(r, "points");
    r = Request(out);
    r.num_pairs = 0;
    fails(r, "pairs");
    r = Request(dir + "/no/such/dir/p.h5");
    fails(r, "does not exist");
    EXPECT_EQ(calls, 0);  // none of the above reached the loader
    r = Request(out);
    r.dataset = "missing";
    fails(r, "dataset 'missing'");
    std::filesystem::remove_all(dir);
}

/// Point-cloud shapes (no mesh, so a scaled copy samples the same indices) times `factor`.
ShapeLoader PointShapesTimes(double factor) {
    return [factor](const std::string&, const std::string&) {
        std::vector<ShapeSource> shapes;
        std::mt19937_64 rng(7);
        for (const ShapeSource& s : test::TestShapes()) {
            const PointCloud points = factor * s.Sample(2000, rng);
            shapes.push_back(ShapeSource::FromPoints(points, "p", "c"));
        }
        return shapes;
    };
}

// Issue 54 item 1: clouds of radius ~150 (millimetres) under the unit-sphere protocol are
// refused, naming the radius and the --scale that fits; with --scale 150 every length is
// multiplied, so the pairs are exactly 150 x those of the unit clouds (same seed: same crops,
// rotations and labels); at scale 1 the pairs are GeneratePairs' of the paper's options.
TEST(Generate, ScaleMultipliesTheProtocolsLengthsAndOffScaleCloudsAreRefused) {
    const std::string dir = testing::FreshTempDir("generate_scale");
    GenerateRequest mm = Request(dir + "/mm.h5");
    mm.options = DefaultProtocolOptions(Protocol::kJitter);  // noise too: every length
    try {
        GenerateToFile(mm, PointShapesTimes(150.0));
        ADD_FAILURE() << "millimetre clouds at scale 1 were accepted";
    } catch (const UsageError& e) {
        // The suggested --scale is the measured radius: crops of shapes of radius <= 150.
        const std::string what = e.what();
        const std::size_t at = what.find("pass --scale ");
        ASSERT_NE(at, std::string::npos) << what;
        const double suggested = std::stod(what.substr(at + 13));
        EXPECT_GT(suggested, 50.0) << what;
        EXPECT_LE(suggested, 150.0) << what;
        EXPECT_NE(what.find("have radius " + what.substr(at + 13, 3)), std::string::npos) << what;
    }
    EXPECT_FALSE(std::filesystem::exists(mm.out));
    mm.scale = 150.0;
    GenerateToFile(mm, PointShapesTimes(150.0));
    GenerateRequest unit = mm;
    unit.scale = 1.0;
    unit.out = dir + "/unit.h5";
    GenerateToFile(unit, PointShapesTimes(1.0));
    const PairSet a = ReadPairFile(unit.out);
    const PairSet b = ReadPairFile(mm.out);
    EXPECT_EQ(b.provenance.at("scale"), 150.0);
    EXPECT_EQ(a.provenance.at("scale"), 1.0);
    EXPECT_EQ(b.provenance.at("params").at("max_translation"), 75.0);
    EXPECT_EQ(b.provenance.at("params").at("eta"), 150.0 * 0.1);
    EXPECT_NEAR(b.provenance.at("source_radius").get<double>(),
                150.0 * a.provenance.at("source_radius").get<double>(), 1e-9);
    ASSERT_EQ(a.pairs.size(), b.pairs.size());
    for (std::size_t k = 0; k < a.pairs.size(); ++k) {
        EXPECT_LT((b.pairs[k].source - 150.0 * a.pairs[k].source).cwiseAbs().maxCoeff(), 1e-9);
        EXPECT_LT((b.pairs[k].target - 150.0 * a.pairs[k].target).cwiseAbs().maxCoeff(), 1e-9);
        EXPECT_LT((Eigen::Vector3d(b.pairs[k].T_gt.topRightCorner<3, 1>()) -
                   150.0 * Eigen::Vector3d(a.pairs[k].T_gt.topRightCorner<3, 1>()))
                      .cwiseAbs()
                      .maxCoeff(),
                  1e-9);
        EXPECT_EQ(a.pairs[k].source_overlap, b.pairs[k].source_overlap);
        EXPECT_EQ(a.pairs[k].target_overlap, b.pairs[k].target_overlap);
    }
    // Scale 1 is the paper's protocol as it was: the pairs GeneratePairs makes of its options.
    const PairSet direct =
        GeneratePairs(PointShapesTimes(1.0)("", ""), unit.options, unit.seed, unit.num_pairs);
    for (std::size_t k = 0; k < a.pairs.size(); ++k) {
        EXPECT_EQ(a.pairs[k].source, direct.pairs[k].source);
        EXPECT_EQ(a.pairs[k].target, direct.pairs[k].target);
        EXPECT_EQ(a.pairs[k].T_gt, direct.pairs[k].T_gt);
    }
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace regbench
