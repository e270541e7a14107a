#include "gmm/permutohedral.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <stdexcept>
#include <tuple>

#include "core/rng.hpp"
#include "core/transform.hpp"
#include "gmm/gmm_common.hpp"
#include "tests/testing/shapes.hpp"

namespace regbench {
namespace {

constexpr float kWeightTol = 1e-5f;

LatticeFeatures RandomFeatures(std::mt19937_64& rng, Eigen::Index n, double scale) {
    LatticeFeatures f(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) f(i, k) = static_cast<float>(scale * StandardNormal(rng));
    }
    return f;
}

TEST(LatticeHashTable, AssignsDenseIdsAndFindsEveryKey) {
    LatticeHashTable table(4);  // starts small: must grow many times
    int id = 0;
    for (int a = -20; a < 20; ++a) {
        for (int b = -10; b < 10; ++b) {
            const int key[3] = {a, b, a - b};
            EXPECT_EQ(table.FindOrInsert(key), id++);
        }
    }
    EXPECT_EQ(table.size(), 800);
    for (int a = -20; a < 20; ++a) {
        for (int b = -10; b < 10; ++b) {
            const int key[3] = {a, b, a - b};
            const int found = table.Find(key);
            ASSERT_GE(found, 0);
            EXPECT_EQ(table.KeyOf(found)[0], a);
            EXPECT_EQ(table.KeyOf(found)[2], a - b);
            EXPECT_EQ(table.FindOrInsert(key), found);  // no duplicate insert
        }
    }
    const int absent[3] = {1000, 0, 0};
    EXPECT_EQ(table.Find(absent), -1);
    EXPECT_EQ(table.size(), 800);
    const int too_big[3] = {LatticeHashTable::kMaxCoordinate + 1, 0, 0};
    EXPECT_THROW(table.FindOrInsert(too_big), std::runtime_error);
    EXPECT_EQ(table.Find(too_big), -1);
}

TEST(PermutohedralLattice, BarycentricWeightsArePositiveAndSumToOne) {
    auto rng = MakePairRng(21, 0);
    const LatticeFeatures f = RandomFeatures(rng, 500, 3.0);
    for (bool blur : {true, false}) {
        const auto elevation = PermutohedralLattice::ElevationFor(blur);
        for (Eigen::Index i = 0; i < f.rows(); ++i) {
            SimplexEmbedding e;
            PermutohedralLattice::Embed(f.row(i).data(), elevation, e);
            float sum = 0.0f;
            std::set<std::tuple<int, int, int>> distinct;
            for (int r = 0; r < PermutohedralLattice::kVertices; ++r) {
                EXPECT_GE(e.weight[r], -kWeightTol);
                sum += e.weight[r];
                distinct.emplace(e.key[r][0], e.key[r][1], e.key[r][2]);
            }
            EXPECT_NEAR(sum, 1.0f, kWeightTol);
            EXPECT_EQ(distinct.size(), 4u);  // a proper simplex
        }
    }
}

TEST(PermutohedralLattice, LatticePointHasAllWeightOnOneVertex) {
    const float origin[3] = {0.0f, 0.0f, 0.0f};
    SimplexEmbedding e;
    PermutohedralLattice::Embed(origin, PermutohedralLattice::ElevationFor(true), e);
    EXPECT_FLOAT_EQ(e.weight[0], 1.0f);
    EXPECT_EQ(e.key[0][0], 0);
    EXPECT_EQ(e.key[0][1], 0);
    EXPECT_EQ(e.key[0][2], 0);
}

TEST(PermutohedralLattice, ElevationScalesAndNormalisationAreTheReferenceOnes) {
    // (d+1) sqrt(2/3) / sqrt(2) for axis 0 with blur, (d+1) sqrt(1/6) / sqrt(2) without.
    EXPECT_NEAR(PermutohedralLattice::ElevationFor(true).scale[0],
                4.0 * std::sqrt(2.0 / 3.0) / std::sqrt(2.0), 1e-6);
    EXPECT_NEAR(PermutohedralLattice::ElevationFor(false).scale[2],
                4.0 * std::sqrt(1.0 / 6.0) / std::sqrt(12.0), 1e-6);
    EXPECT_NEAR(PermutohedralLattice::SliceNormalisation(), 1.0 / (1.0 + 0.125), 1e-7);
    EXPECT_EQ(PermutohedralLattice::ReferencePadding(1434), 2);
    EXPECT_EQ(PermutohedralLattice::ReferencePadding(1436), 0);
}

TEST(PermutohedralLattice, FilterIsLinearAndUnblurredIsSymmetric) {
    // Splat, blur and slice are linear. Without blur the slice is the splat's transpose, so
    // the filter matrix K is symmetric: (K e_j)_i == (K e_i)_j. (The per-axis blurs do not
    // commute on a sparse lattice, so the blurred K is not.)
    auto rng = MakePairRng(22, 0);
    const LatticeFeatures f = RandomFeatures(rng, 40, 0.8);
    for (bool blur : {true, false}) {
        PermutohedralLattice lattice;
        ASSERT_TRUE(lattice.Build(f, blur));
        LatticeValues K(40, 40);
        for (int j = 0; j < 40; ++j) {
            LatticeValues e = LatticeValues::Zero(40, 1);
            e(j, 0) = 1.0f;
            K.col(j) = lattice.Filter(e).col(0);
        }
        if (!blur) {
            EXPECT_LT((K - K.transpose()).cwiseAbs().maxCoeff(), 1e-6f);
        }
        EXPECT_GT(K.diagonal().minCoeff(), 0.0f) << "blur " << blur;
        LatticeValues v(40, 2);
        for (int i = 0; i < 40; ++i) v.row(i) << static_cast<float>(i), 1.0f;
        const LatticeValues out = lattice.Filter(v);
        EXPECT_LT((out.col(0) - K * v.col(0)).cwiseAbs().maxCoeff(), 1e-4f) << "blur " << blur;
        EXPECT_LT((out.col(1) - K * v.col(1)).cwiseAbs().maxCoeff(), 1e-5f) << "blur " << blur;
    }
}

TEST(PermutohedralLattice, BlurWidensTheKernel) {
    // Two points 1.5 feature units apart: beyond the tent of the unblurred lattice
    // (spacing ~2.1 sigma, but the elevation differs), within reach of the blurred one.
    LatticeFeatures f(2, 3);
    f << 0.0f, 0.0f, 0.0f, 1.5f, 0.0f, 0.0f;
    LatticeValues v(2, 1);
    v << 1.0f, 0.0f;
    PermutohedralLattice blurred;
    blurred.Build(f, true);
    const float with_blur = blurred.Filter(v)(1, 0);
    PermutohedralLattice plain;
    plain.Build(f, false);
    const float without_blur = plain.Filter(v)(1, 0);
    EXPECT_GT(with_blur, 0.0f);
    EXPECT_GT(with_blur, without_blur);
}

TEST(PermutohedralLattice, SliceAtMatchesInsertingZeroValuedQueries) {
    auto rng = MakePairRng(23, 0);
    const LatticeFeatures data = RandomFeatures(rng, 300, 1.5);
    const LatticeFeatures queries = RandomFeatures(rng, 200, 1.5);
    LatticeValues values(300, 3);
    for (int i = 0; i < 300; ++i) values.row(i) << 1.0f, data(i, 0), data(i, 1);

    PermutohedralLattice plain;
    plain.Build(data, false);
    const LatticeValues vertex_values = plain.Splat(values, 0, 300);
    LatticeValues sliced;
    plain.SliceAt(queries, vertex_values, sliced);

    LatticeFeatures all(500, 3);
    all << data, queries;
    LatticeValues all_values = LatticeValues::Zero(500, 3);
    all_values.topRows(300) = values;
    PermutohedralLattice joint;
    joint.Build(all, false);
    const LatticeValues reference = joint.Filter(all_values).bottomRows(200);
    EXPECT_LT((sliced - reference).cwiseAbs().maxCoeff(), 1e-6f);
    EXPECT_GT(sliced.col(0).maxCoeff(), 0.0f);

    PermutohedralLattice blurred;
    blurred.Build(data, true);
    EXPECT_THROW(blurred.SliceAt(queries, blurred.Splat(values, 0, 300), sliced), std::logic_error);
    EXPECT_THROW(plain.Blur(sliced), std::logic_error);
}

TEST(PermutohedralLattice, StopsEarlyAtMaxVertices) {
    auto rng = MakePairRng(24, 0);
    const LatticeFeatures f = RandomFeatures(rng, 200, 2.0);
    PermutohedralLattice full;
    ASSERT_TRUE(full.Build(f, true));
    ASSERT_GT(full.NumVertices(), 20);
    PermutohedralLattice capped;
    EXPECT_FALSE(capped.Build(f, true, 20));
    EXPECT_GT(capped.NumVertices(), 20);
    EXPECT_LT(capped.NumVertices(), full.NumVertices());
    EXPECT_THROW(capped.Splat(LatticeValues::Ones(200, 1), 0, 200), std::logic_error);
    PermutohedralLattice roomy;
    EXPECT_TRUE(roomy.Build(f, true, full.NumVertices()));
    EXPECT_EQ(roomy.NumVertices(), full.NumVertices());
}

TEST(PermutohedralLattice, RejectsNonFiniteFeatures) {
    LatticeFeatures f = LatticeFeatures::Zero(3, 3);
    f(1, 2) = std::nanf("");
    PermutohedralLattice lattice;
    EXPECT_THROW(lattice.Build(f, false), std::runtime_error);
    f(1, 2) = 1e9f;
    EXPECT_THROW(lattice.Build(f, false), std::runtime_error);
}

// Spec test 4: on the 717 + 717 ellipsoid (target turned 30 deg about z), at sigma2 = sqsum,
// probreg's blurred lattice is too big (> 0.015 N vertices) and the unblurred one is coarse.
TEST(PermutohedralLattice, EllipsoidAtSqsumIsTooBigToBlurAndCoarseWithout) {
    const PointCloud Y = testing::EllipsoidSurface(717, 7);
    const PointCloud X = Apply(
        MakeTransform(RotationFromAxisAngle({0, 0, 1}, M_PI / 6.0), Eigen::Vector3d::Zero()), Y);
    const double sigma2 = SquaredDistanceMean(Y, X);
    EXPECT_NEAR(sigma2, 0.29, 0.03);
    const double sigma = std::sqrt(sigma2);
    // [Y/sigma; X/sigma] plus the reference's padding slots (1434 = 4 * 358 + 2).
    const int pad = PermutohedralLattice::ReferencePadding(1434);
    LatticeFeatures f = LatticeFeatures::Zero(1434 + pad, 3);
    f.topRows(717) = (Y / sigma).cast<float>();
    f.middleRows(717, 717) = (X / sigma).cast<float>();
    PermutohedralLattice blurred;
    blurred.Build(f, true);
    EXPECT_GT(blurred.NumVertices(), 0.015 * 717);
    PermutohedralLattice plain;
    plain.Build(f, false);
    EXPECT_GE(plain.NumVertices(), 10);
    EXPECT_LE(plain.NumVertices(), 30);
    EXPECT_LT(plain.NumVertices(), blurred.NumVertices());
}

}  // namespace
}  // namespace regbench
