// Test sets as the authors evaluate them: one pair per item (`--pairs all`), stored pairs
// (`--pairing stored`), the noise-free shared complete-to-complete variant, and the provenance
// each pair file records. Expected values are hand derivations stated beside each check.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <set>

#include "core/transform.hpp"
#include "protocols/generate.hpp"
#include "protocols/pair_file.hpp"
#include "protocols/pair_protocols.hpp"
#include "protocols/pair_summary.hpp"
#include "tests/protocols/test_shapes.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

/// Loader returning the three in-test shapes (two meshes, one cloud) for dataset "test".
ShapeLoader TestLoader() {
    return [](const std::string&, const std::string&) { return test::TestShapes(); };
}

/// A rotation of 30 degrees about z and a translation (1, 2, 3): rigid by construction.
Transform KnownMotion() {
    const double c = std::cos(kPi / 6.0), s = std::sin(kPi / 6.0);
    Transform T = Transform::Identity();
    T.topLeftCorner<3, 3>() << c, -s, 0, s, c, 0, 0, 0, 1;
    T.topRightCorner<3, 1>() << 1, 2, 3;
    return T;
}

TEST(PairsAll, OnePairPerItemUsesEveryShapeOnce) {
    const std::string dir = testing::FreshTempDir("pairs_all").string();
    GenerateRequest r;
    r.dataset = "test";
    r.one_per_item = true;
    r.seed = 3;
    r.out = dir + "/all.h5";
    GenerateToFile(r, TestLoader());
    const PairSet set = ReadPairFile(r.out);
    // TestShapes() holds 3 shapes, one level: 3 pairs, pair k on shape k.
    ASSERT_EQ(set.pairs.size(), 3u);
    EXPECT_EQ(set.pairs[0].shape, "ellipsoid");
    EXPECT_EQ(set.pairs[1].shape, "ellipsoid2");
    EXPECT_EQ(set.pairs[2].shape, "cloud");
    EXPECT_EQ(set.provenance.at("pair_selection"), "one-per-item");
    EXPECT_EQ(set.provenance.at("num_pairs"), 3);

    // A fixed count cycles instead: 2 pairs of 3 shapes never reach the third one.
    r.one_per_item = false;
    r.num_pairs = 2;
    r.out = dir + "/two.h5";
    GenerateToFile(r, TestLoader());
    const PairSet two = ReadPairFile(r.out);
    EXPECT_EQ(two.provenance.at("pair_selection"), "cycle");
    std::set<std::string> used;
    for (const auto& p : two.pairs) used.insert(p.shape);
    EXPECT_EQ(used.count("cloud"), 0u);
    std::filesystem::remove_all(dir);
}

TEST(PairsAll, OverlapSweepGetsEveryShapeAtEveryLevel) {
    const std::string dir = testing::FreshTempDir("pairs_all_sweep").string();
    GenerateRequest r;
    r.dataset = "test";
    r.one_per_item = true;
    r.options = DefaultProtocolOptions(Protocol::kOverlapSweep);
    r.options.sweep_keeps = {0.4, 0.8};
    r.out = dir + "/sweep.h5";
    GenerateToFile(r, TestLoader());
    const PairSet set = ReadPairFile(r.out);
    // 3 shapes x 2 levels = 6 pairs; each (shape, keep) exactly once.
    ASSERT_EQ(set.pairs.size(), 6u);
    std::map<std::pair<std::string, double>, int> seen;
    for (const auto& p : set.pairs) ++seen[{p.shape, p.meta.at("source_keep").get<double>()}];
    EXPECT_EQ(seen.size(), 6u);
    for (const auto& [key, count] : seen) EXPECT_EQ(count, 1) << key.first << " " << key.second;
    std::filesystem::remove_all(dir);
}

/// A stored pair with hand-placed points: target[i] = T source[i] for i < 3, and one far point
/// on each side, so the eta = 0.1 labels are known without a kd-tree.
ShapeSource HandStoredPair(const Transform& T) {
    PointCloud source(4, 3);
    source << 0, 0, 0, 0.5, 0, 0, 0, 0.5, 0, 50, 50, 50;
    PointCloud target = Apply(T, source);
    target.row(3) << -50, -50, -50;  // nowhere near T source[3] = T (50, 50, 50)
    return ShapeSource::FromStoredPair(source, target, T, "scan0", "icl_nuim");
}

TEST(StoredPairing, UsesTheFileCloudsAndTransformAsStored) {
    const Transform T = KnownMotion();
    ProtocolOptions o = DefaultProtocolOptions(Protocol::kIndoor);
    o.pairing = Pairing::kStored;
    const std::vector<ShapeSource> shapes = {HandStoredPair(T)};
    const Pair p = GeneratePair(shapes, o, /*seed=*/1, /*pair_index=*/0);
    ASSERT_EQ(p.source.rows(), 4);  // 4 < points (2048): the whole stored cloud
    EXPECT_EQ(p.source, shapes[0].stored_source());
    EXPECT_EQ(p.target, shapes[0].stored_target());
    EXPECT_LT((p.T_gt - T).cwiseAbs().maxCoeff(), 1e-12);
    // Points 0-2 coincide after T (distance 0 < eta); point 3 is ~170 away on both sides.
    EXPECT_EQ(p.source_overlap.cast<int>(), Eigen::Vector4i(1, 1, 1, 0));
    EXPECT_EQ(p.target_overlap.cast<int>(), Eigen::Vector4i(1, 1, 1, 0));
    EXPECT_DOUBLE_EQ(p.source_overlap_ratio, 0.75);
    // The seed changes nothing: the pair is the file's.
    const Pair q = GeneratePair(shapes, o, /*seed=*/99, /*pair_index=*/0);
    EXPECT_EQ(q.source, p.source);
    EXPECT_EQ(q.T_gt, p.T_gt);
    // `points` cuts each cloud to its first rows, as DeepGMR's loader slices [:n_points].
    o.points = 3;
    const Pair cut = GeneratePair(shapes, o, 1, 0);
    ASSERT_EQ(cut.source.rows(), 3);
    EXPECT_EQ(cut.target.rows(), 3);
    EXPECT_EQ(cut.source, shapes[0].stored_source().topRows(3));
}

TEST(StoredPairing, RefusesShapesWithoutStoredPairsAndNonRigidTransforms) {
    ProtocolOptions o = DefaultProtocolOptions(Protocol::kIndoor);
    o.pairing = Pairing::kStored;
    try {
        GeneratePair(test::TestShapes(), o, 1, 0);
        ADD_FAILURE() << "a mesh shape has no stored pair";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("'ellipsoid' stores none"), std::string::npos)
            << e.what();
    }
    Transform scaled = KnownMotion();
    scaled.topLeftCorner<3, 3>() *= 1.1;  // R^T R = 1.21 I: not rigid
    PointCloud c = PointCloud::Random(5, 3);
    try {
        ShapeSource::FromStoredPair(c, c, scaled, "scan7", "icl_nuim");
        ADD_FAILURE() << "a scaled transform is not rigid";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("'scan7'"), std::string::npos) << e.what();
    }
    ProtocolOptions sweep = DefaultProtocolOptions(Protocol::kOverlapSweep);
    sweep.pairing = Pairing::kStored;
    EXPECT_THROW(ValidateProtocolOptions(sweep), std::invalid_argument);
    EXPECT_EQ(ParsePairing("stored"), Pairing::kStored);
    EXPECT_EQ(ToString(Pairing::kStored), "stored");
}

TEST(StoredPairing, ProvenanceSaysWhatWasUsed) {
    ProtocolOptions o = DefaultProtocolOptions(Protocol::kIndoor);
    o.pairing = Pairing::kStored;
    const nlohmann::json p = ProtocolProvenance(o);
    EXPECT_EQ(p.at("pairing"), "stored");
    EXPECT_EQ(p.at("noise_sigma"), 0.0);
    EXPECT_TRUE(p.contains("stored_pairs"));
    // Issue 41: stored pairs said protocol "indoor" / "partial" with its keep 0.7 and noise
    // 0.01, none of which was applied: they are labelled `stored`, with what was applied.
    EXPECT_EQ(p.at("protocol"), "stored");
    EXPECT_EQ(p.at("params"),
              (nlohmann::json{{"points", o.points}, {"pairing", "stored"}, {"eta", o.eta}}));
    // One noise_sigma: a protocol without noise carries no noise parameters in params.
    const nlohmann::json partial = ProtocolProvenance(DefaultProtocolOptions(Protocol::kPartial));
    EXPECT_EQ(partial.at("noise_sigma"), 0.0);
    EXPECT_FALSE(partial.at("params").contains("noise_sigma"));
    EXPECT_FALSE(partial.at("params").contains("noise_clip"));
    EXPECT_EQ(partial.at("params").at("keep"), 0.7);
    const nlohmann::json jitter = ProtocolProvenance(DefaultProtocolOptions(Protocol::kJitter));
    EXPECT_EQ(jitter.at("pairing"), "independent");
    EXPECT_EQ(jitter.at("noise_sigma"), 0.01);               // the protocol's default sigma
    EXPECT_EQ(jitter.at("params").at("noise_sigma"), 0.01);  // applied: the same one
    EXPECT_FALSE(jitter.contains("stored_pairs"));
}

TEST(CleanComplete, SharedNoiseFreePairsHaveAZeroCcdFloor) {
    // Complete clouds from one shared sample without noise: the ground truth maps every
    // source point exactly onto a target point (same sample point, shuffled), so the CCD of
    // T_gt is 0 up to rounding. The noisy independent protocol cannot reach that: two
    // independent samples of a surface never coincide, and noise adds sigma-sized offsets.
    const std::vector<ShapeSource> shapes = test::TestShapes();
    ProtocolOptions clean = DefaultProtocolOptions(Protocol::kComplete);
    clean.pairing = Pairing::kShared;
    clean.noise_sigma = 0.0;
    const PairSet a = GeneratePairs(shapes, clean, 5, 3);
    EXPECT_EQ(a.provenance.at("noise_sigma"), 0.0);
    EXPECT_EQ(a.provenance.at("pairing"), "shared");
    EXPECT_EQ(a.pairs[0].source.rows(), 1024);
    EXPECT_LT(SummarizePairSet(a).gt_ccd_mean, 1e-9);
    const PairSet noisy = GeneratePairs(shapes, DefaultProtocolOptions(Protocol::kComplete), 5, 3);
    EXPECT_EQ(noisy.provenance.at("noise_sigma"), 0.01);
    EXPECT_GT(SummarizePairSet(noisy).gt_ccd_mean, 0.005);
}

}  // namespace
}  // namespace regbench
