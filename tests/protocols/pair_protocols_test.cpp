#include "protocols/pair_protocols.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <set>

#include "core/rng.hpp"
#include "core/transform.hpp"
#include "protocols/pair_file.hpp"
#include "tests/protocols/test_shapes.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

constexpr double kAngleTol = 1e-9;
constexpr double kEps = 1e-12;

/// (x, y, z) of R = Rx(x) Ry(y) Rz(z) in degrees (valid for |y| < 90).
Eigen::Vector3d XyzAnglesDeg(const Eigen::Matrix3d& R) {
    const double y = std::asin(std::clamp(R(0, 2), -1.0, 1.0));
    const double x = std::atan2(-R(1, 2), R(2, 2));
    const double z = std::atan2(-R(0, 1), R(0, 0));
    return Eigen::Vector3d(x, y, z) * 180.0 / M_PI;
}

std::size_t DistinctRows(const PointCloud& c) {
    std::set<std::array<double, 3>> rows;
    for (Eigen::Index i = 0; i < c.rows(); ++i) rows.insert({c(i, 0), c(i, 1), c(i, 2)});
    return rows.size();
}

TEST(Crop, KeepsExactlyRoundedCountAboveQuantile) {
    std::mt19937_64 rng = MakePairRng(3, 0);
    const PointCloud cloud = test::TestShapes()[0].Sample(1024, rng);
    std::mt19937_64 crop_rng = MakePairRng(3, 1);
    std::mt19937_64 replay = crop_rng;  // the crop's first draws are its direction
    const Eigen::Vector3d n = RandomUnitVector(replay);
    const std::vector<Eigen::Index> kept = CropIndices(cloud, 0.7, crop_rng);
    ASSERT_EQ(kept.size(), 717u);
    EXPECT_EQ(CropCount(1024, 0.7), 717);
    // Hand arithmetic: 0.7 * 1024 = 716.8, 0.7 * 2048 = 1433.6.
    EXPECT_EQ(CropCount(1024, 0.7, CropRounding::kFloor), 716);
    EXPECT_EQ(CropCount(2048, 0.7, CropRounding::kFloor), 1433);
    EXPECT_EQ(CropCount(2048, 0.7, CropRounding::kNearest), 1434);
    EXPECT_EQ(CropRoundingFor(Protocol::kIndoor), CropRounding::kFloor);
    EXPECT_EQ(CropRoundingFor(Protocol::kPartial), CropRounding::kNearest);
    // Every kept point projects above every dropped one: a half-space cut along n.
    const Eigen::RowVector3d c = cloud.colwise().mean();
    std::vector<char> in(1024, 0);
    for (auto i : kept) in[static_cast<std::size_t>(i)] = 1;
    double min_kept = 1e9, max_dropped = -1e9;
    for (Eigen::Index i = 0; i < 1024; ++i) {
        const double d = (cloud.row(i) - c).dot(n.transpose());
        if (in[static_cast<std::size_t>(i)])
            min_kept = std::min(min_kept, d);
        else
            max_dropped = std::max(max_dropped, d);
    }
    EXPECT_GT(min_kept, max_dropped);
}

TEST(Protocols, PartialPairsHave717PointsEach) {
    const auto shapes = test::TestShapes();
    for (Pairing pairing : {Pairing::kIndependent, Pairing::kShared}) {
        ProtocolOptions o;
        o.pairing = pairing;
        for (std::uint64_t k = 0; k < 3; ++k) {
            const Pair p = GeneratePair(shapes, o, 11, k);
            EXPECT_EQ(p.source.rows(), 717);
            EXPECT_EQ(p.target.rows(), 717);
            EXPECT_EQ(p.source_overlap.size(), 717);
        }
    }
}

TEST(Motion, EulerAnglesAndTranslationsStayInRange) {
    std::mt19937_64 rng = MakePairRng(5, 0);
    Eigen::Vector3d max_angle = Eigen::Vector3d::Constant(-1.0);
    for (int i = 0; i < 2000; ++i) {
        const Transform T = DrawMotion(MotionConvention::kEuler, 45.0, 0.5, rng);
        const Eigen::Vector3d a = XyzAnglesDeg(T.topLeftCorner<3, 3>());
        EXPECT_GE(a.minCoeff(), -kAngleTol);
        EXPECT_LE(a.maxCoeff(), 45.0 + kAngleTol);
        EXPECT_LE((T.topRightCorner<3, 1>().cwiseAbs().maxCoeff()), 0.5);
        max_angle = max_angle.cwiseMax(a);
    }
    // The draws cover the range (not a degenerate constant).
    EXPECT_GT(max_angle.minCoeff(), 44.0);
}

TEST(Motion, IndependentPairsMoveTheTargetWithTheDrawnMotion) {
    const auto shapes = test::TestShapes();
    ProtocolOptions o;
    for (std::uint64_t k = 0; k < 20; ++k) {
        const Pair p = GeneratePair(shapes, o, 1, k);
        const Eigen::Vector3d a = XyzAnglesDeg(p.T_gt.topLeftCorner<3, 3>());
        EXPECT_GE(a.minCoeff(), -kAngleTol);
        EXPECT_LE(a.maxCoeff(), 45.0 + kAngleTol);
        EXPECT_LE((p.T_gt.topRightCorner<3, 1>().cwiseAbs().maxCoeff()), 0.5);
    }
}

TEST(Motion, AxisAngleWithinLimits) {
    std::mt19937_64 rng = MakePairRng(9, 0);
    for (int i = 0; i < 500; ++i) {
        const Transform T = DrawMotion(MotionConvention::kAxisAngle, 45.0, 0.25, rng);
        EXPECT_LE(RotationAngleDeg(Eigen::Matrix3d::Identity(), T.topLeftCorner<3, 3>()),
                  45.0 + kAngleTol);
        EXPECT_LE((T.topRightCorner<3, 1>().norm()), 0.25 + kEps);
    }
}

TEST(Noise, IsClippedPerCoordinate) {
    std::mt19937_64 rng = MakePairRng(2, 0);
    PointCloud cloud = PointCloud::Zero(2000, 3);
    AddClippedNoise(cloud, 1.0, 0.05, rng);
    EXPECT_LE(cloud.cwiseAbs().maxCoeff(), 0.05);
    EXPECT_DOUBLE_EQ(cloud.cwiseAbs().maxCoeff(), 0.05);  // sigma 1 hits the clip
    PointCloud small = PointCloud::Zero(2000, 3);
    AddClippedNoise(small, 0.01, 0.05, rng);
    const double std_dev = std::sqrt(small.array().square().mean());
    EXPECT_NEAR(std_dev, 0.01, 0.001);
}

TEST(Protocols, JitterDiffersFromPartialOnlyByClippedNoise) {
    // Same seed, same draws up to the noise: the clouds differ by at most the clip.
    const auto shapes = test::TestShapes();
    ProtocolOptions partial;
    ProtocolOptions jitter = DefaultProtocolOptions(Protocol::kJitter);
    const Pair a = GeneratePair(shapes, partial, 4, 2);
    const Pair b = GeneratePair(shapes, jitter, 4, 2);
    ASSERT_EQ(a.source.rows(), b.source.rows());
    const double diff = (a.source - b.source).cwiseAbs().maxCoeff();
    EXPECT_GT(diff, 0.0);
    EXPECT_LE(diff, 0.05 + kEps);
}

TEST(Density, HalvesDistinctPointsAndKeepsCount) {
    std::mt19937_64 rng = MakePairRng(8, 0);
    const std::vector<Eigen::Index> idx = ThinAndRepeat(717, 0.5, rng);
    EXPECT_EQ(idx.size(), 717u);
    EXPECT_EQ(std::set<Eigen::Index>(idx.begin(), idx.end()).size(), 359u);

    const auto shapes = test::TestShapes();
    for (Pairing pairing : {Pairing::kIndependent, Pairing::kShared}) {
        ProtocolOptions o = DefaultProtocolOptions(Protocol::kDensity);
        o.pairing = pairing;
        const Pair p = GeneratePair(shapes, o, 3, 0);
        EXPECT_EQ(p.target.rows(), 717);
        EXPECT_EQ(DistinctRows(p.target), 359u);
        EXPECT_EQ(DistinctRows(p.source), 717u);
    }
}

TEST(Protocols, CompleteAndCompleteToPartialCounts) {
    const auto shapes = test::TestShapes();
    const Pair c = GeneratePair(shapes, DefaultProtocolOptions(Protocol::kComplete), 1, 0);
    EXPECT_EQ(c.source.rows(), 1024);
    EXPECT_EQ(c.target.rows(), 1024);
    const Pair cp =
        GeneratePair(shapes, DefaultProtocolOptions(Protocol::kCompleteToPartial), 1, 0);
    EXPECT_EQ(cp.source.rows(), 717);
    EXPECT_EQ(cp.target.rows(), 1024);
    const Pair in = GeneratePair(shapes, DefaultProtocolOptions(Protocol::kIndoor), 1, 2);
    EXPECT_EQ(in.shape, "cloud");  // the point-cloud source
    // The authors' indoor loader keeps int(0.7 * 2048) = 1433 points (floor), not round's 1434.
    EXPECT_EQ(in.source.rows(), 1433);
    EXPECT_EQ(in.target.rows(), 1433);
}

TEST(Protocols, OverlapSweepCyclesKeepLevelsAndOverlapGrowsWithKeep) {
    const auto shapes = test::TestShapes();
    ProtocolOptions o = DefaultProtocolOptions(Protocol::kOverlapSweep);
    o.sweep_keeps = {0.4, 0.9};
    double overlap[2] = {0.0, 0.0};
    constexpr int kPerLevel = 12;
    for (std::uint64_t k = 0; k < 2 * kPerLevel; ++k) {
        const Pair p = GeneratePair(shapes, o, 6, k);
        EXPECT_EQ(p.source.rows(), CropCount(1024, o.sweep_keeps[k % 2]));
        EXPECT_DOUBLE_EQ(p.meta.at("source_keep").get<double>(), o.sweep_keeps[k % 2]);
        overlap[k % 2] += p.source_overlap_ratio / kPerLevel;
    }
    EXPECT_LT(overlap[0] + 0.2, overlap[1]);
}

TEST(Overlap, PartialPairsHavePlausibleMeasuredOverlap) {
    const auto shapes = test::TestShapes();
    for (Pairing pairing : {Pairing::kIndependent, Pairing::kShared}) {
        ProtocolOptions o;
        o.pairing = pairing;
        double mean = 0.0;
        constexpr int kPairs = 30;
        for (int k = 0; k < kPairs; ++k) {
            const Pair p = GeneratePair(shapes, o, 21, static_cast<std::uint64_t>(k));
            EXPECT_NEAR(p.source_overlap_ratio, p.source_overlap.cast<double>().mean(), kEps);
            mean += p.source_overlap_ratio / kPairs;
        }
        std::cout << "[ overlap  ] mean source overlap, partial, " << ToString(pairing) << ": "
                  << mean << "\n";
        // Two 70% crops of one surface share 40%..100% of their points on average.
        EXPECT_GT(mean, 0.4);
        EXPECT_LT(mean, 0.98);
    }
}

TEST(Overlap, RadiusLabelsMatchBruteForce) {
    const auto shapes = test::TestShapes();
    const Pair p = GeneratePair(shapes, ProtocolOptions{}, 2, 0);
    const PointCloud moved = Apply(p.T_gt, p.source);
    for (Eigen::Index i = 0; i < moved.rows(); i += 37) {
        const double d = (p.target.rowwise() - moved.row(i)).rowwise().norm().minCoeff();
        EXPECT_EQ(p.source_overlap(i), d < 0.1 ? 1 : 0);
    }
}

TEST(Overlap, SharedLabelsMarkExactCorrespondences) {
    // Without noise, a shared-sample point labelled overlapping has an exact twin in the target.
    const auto shapes = test::TestShapes();
    ProtocolOptions o;
    o.pairing = Pairing::kShared;
    const Pair p = GeneratePair(shapes, o, 2, 1);
    const PointCloud moved = Apply(p.T_gt, p.source);
    for (Eigen::Index i = 0; i < moved.rows(); ++i) {
        const double d = (p.target.rowwise() - moved.row(i)).rowwise().norm().minCoeff();
        EXPECT_EQ(p.source_overlap(i) == 1, d < 1e-9) << "point " << i;
    }
}

TEST(Reproducibility, PairKDoesNotChangeWhenMorePairsAreGenerated) {
    const auto shapes = test::TestShapes();
    const ProtocolOptions o = DefaultProtocolOptions(Protocol::kJitter);
    const PairSet small = GeneratePairs(shapes, o, 77, 3);
    const PairSet large = GeneratePairs(shapes, o, 77, 8);
    for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(small.pairs[k].source, large.pairs[k].source);
        EXPECT_EQ(small.pairs[k].target, large.pairs[k].target);
        EXPECT_EQ(small.pairs[k].T_gt, large.pairs[k].T_gt);
        EXPECT_EQ(small.pairs[k].shape, large.pairs[k].shape);
    }
    // And a pair generated alone equals its place in the set.
    EXPECT_EQ(GeneratePair(shapes, o, 77, 6).target, large.pairs[6].target);
    EXPECT_NE(GeneratePair(shapes, o, 78, 6).target, large.pairs[6].target);
}

TEST(Reproducibility, SameSeedGivesByteIdenticalFiles) {
    const auto shapes = test::TestShapes();
    const std::string dir = testing::FreshTempDir("bytes");
    const ProtocolOptions o = DefaultProtocolOptions(Protocol::kJitter);
    WritePairFile(dir + "/a.h5", GeneratePairs(shapes, o, 5, 4));
    WritePairFile(dir + "/b.h5", GeneratePairs(shapes, o, 5, 4));
    WritePairFile(dir + "/c.h5", GeneratePairs(shapes, o, 6, 4));
    const std::string a = testing::ReadBytes(dir + "/a.h5");
    ASSERT_GT(a.size(), 1000u);
    EXPECT_EQ(a, testing::ReadBytes(dir + "/b.h5"));
    EXPECT_NE(a, testing::ReadBytes(dir + "/c.h5"));
    const PairSet back = ReadPairFile(dir + "/a.h5");
    EXPECT_EQ(back.provenance.at("params").at("eta").get<double>(), 0.1);
    EXPECT_EQ(back.provenance.at("params").at("pairing").get<std::string>(), "independent");
    EXPECT_EQ(back.pairs[1].meta.at("target_keep").get<double>(), 0.7);
    std::filesystem::remove_all(dir);
}

TEST(Options, ImpossibleParametersAreRejectedByName) {
    const auto expect_throw = [](ProtocolOptions o, const std::string& name) {
        try {
            ValidateProtocolOptions(o);
            ADD_FAILURE() << "no error for " << name;
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        }
    };
    ProtocolOptions o;
    o.keep = 1.5;
    expect_throw(o, "keep");
    o.keep = 0.0;
    expect_throw(o, "keep");
    o = ProtocolOptions{};
    o.points = 2;
    expect_throw(o, "points");
    o = ProtocolOptions{};
    o.eta = 0.0;
    expect_throw(o, "eta");
    o = DefaultProtocolOptions(Protocol::kOverlapSweep);
    o.sweep_keeps = {0.5, 1.2};
    expect_throw(o, "sweep_keeps");
    EXPECT_NO_THROW(ValidateProtocolOptions(ProtocolOptions{}));
    EXPECT_THROW(ParseProtocol("partial-ish"), std::invalid_argument);
    EXPECT_THROW(GeneratePairs(
                     test::TestShapes(),
                     [] {
                         ProtocolOptions bad;
                         bad.keep = 2.0;
                         return bad;
                     }(),
                     0, 5),
                 std::invalid_argument);
}

TEST(Options, JsonRoundTripAndUnknownKeys) {
    ProtocolOptions o = DefaultProtocolOptions(Protocol::kIndoor);
    o.pairing = Pairing::kShared;
    o.motion = MotionConvention::kAxisAngle;
    const nlohmann::json j = o;
    const ProtocolOptions back = j.get<ProtocolOptions>();
    EXPECT_EQ(nlohmann::json(back), j);
    EXPECT_EQ(back.points, 2048);
    const ProtocolOptions partial;
    EXPECT_THROW(ProtocolOptionsFromJson({{"kep", 0.5}}, partial), std::invalid_argument);
    EXPECT_THROW(ProtocolOptionsFromJson({{"pairing", "both"}}, partial), std::invalid_argument);
    EXPECT_THROW(ProtocolOptionsFromJson({{"keep", "0.5"}}, partial), std::invalid_argument);
}

TEST(Options, PartialJsonReadsOverTheNamedProtocolsDefaults) {
    // Defaults by hand: indoor samples 2048 points (the paper's Tab. 3), the others 1024.
    EXPECT_EQ(ProtocolOptionsFromJson({{"protocol", "indoor"}}, ProtocolOptions{}).points, 2048);
    ProtocolOptions base;
    base.keep = 0.5;
    const ProtocolOptions o = ProtocolOptionsFromJson({{"noise_sigma", 0.02}}, base);
    EXPECT_EQ(o.keep, 0.5);
    EXPECT_EQ(o.noise_sigma, 0.02);
    EXPECT_EQ(o.points, 1024);
    EXPECT_EQ(ProtocolOptionsFromJson(nullptr, base).keep, 0.5);
}

/// The message ProtocolOptionsFromJson refuses `j` with ("" when it reads it).
std::string ProtocolRefusal(const nlohmann::json& j) {
    try {
        ProtocolOptionsFromJson(j, ProtocolOptions{});
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "";
}

TEST(Options, IntegerKeysFollowTheOneRule) {
    // As every method parameter and config: 717.0 is the whole number 717, 717.5 is refused
    // (it used to be truncated to 717 silently), and 1e12 too (it used to reach
    // ValidateProtocolOptions as -2147483648: "must be >= 3, got -2147483648").
    EXPECT_EQ(ProtocolOptionsFromJson({{"points", 717.0}}, ProtocolOptions{}).points, 717);
    const std::string fraction = ProtocolRefusal({{"points", 717.5}});
    EXPECT_NE(fraction.find("'points' must be a whole number"), std::string::npos) << fraction;
    const std::string huge = ProtocolRefusal({{"points", 1e12}});
    EXPECT_NE(huge.find("'points' is out of range"), std::string::npos) << huge;
}

TEST(ShapeSource, PointSourceSamplesDistinctPointsAndRejectsTooFew) {
    PointCloud pts(10, 3);
    for (int i = 0; i < 10; ++i) pts.row(i) << i, 0, 0;
    const ShapeSource s = ShapeSource::FromPoints(pts, "line", "x");
    std::mt19937_64 rng(1);
    const PointCloud sample = s.Sample(10, rng);
    EXPECT_EQ(DistinctRows(sample), 10u);
    EXPECT_THROW(s.Sample(11, rng), std::invalid_argument);
}

TEST(ShapeSource, MeshSamplesLieOnTheSurface) {
    const ShapeSource s = ShapeSource::FromMesh(test::EllipsoidMesh(1, 1, 1, 40, 80), "sphere", "");
    std::mt19937_64 rng(1);
    const PointCloud sample = s.Sample(2000, rng);
    const Eigen::VectorXd r = sample.rowwise().norm();
    EXPECT_GT(r.minCoeff(), 0.99);  // chords of a fine UV sphere stay close to radius 1
    EXPECT_LE(r.maxCoeff(), 1.0 + kEps);
    // Area-weighted: the two hemispheres get about half the points each.
    const double upper = (sample.col(2).array() > 0).cast<double>().mean();
    EXPECT_NEAR(upper, 0.5, 0.05);
}

TEST(ShapeSource, MeshSamplingMatchesSampleSurfaceDrawForDraw) {
    // The cached area table must not change the samples: same rng, same points as mesh.hpp.
    const Mesh mesh = test::EllipsoidMesh(1.0, 0.6, 0.4);
    const ShapeSource s = ShapeSource::FromMesh(mesh, "e", "");
    std::mt19937_64 a(42), b(42);
    EXPECT_EQ(s.Sample(500, a), SampleSurface(mesh, 500, b));
}

}  // namespace
}  // namespace regbench
