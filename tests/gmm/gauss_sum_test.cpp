#include "gmm/gauss_sum.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.hpp"
#include "core/synthetic_shapes.hpp"
#include "core/transform.hpp"

namespace regbench {
namespace {

constexpr double kFastExpRelTol = 3e-7;  // the bound documented in gauss_sum.hpp
constexpr double kSumRelTol = 2e-5;      // float kernels, double accumulation

double MaxRelDiff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
    return (a - b).cwiseAbs().maxCoeff() / std::max(b.cwiseAbs().maxCoeff(), 1e-300);
}

TEST(FastExp, MatchesStdExpWithinBound) {
    double worst = 0.0;
    for (int i = 0; i <= 2000000; ++i) {
        const float x = -87.0f * static_cast<float>(i) / 2000000.0f;
        const double ref = std::exp(static_cast<double>(x));
        worst = std::max(worst, std::abs(FastExp(x) - ref) / ref);
    }
    EXPECT_LT(worst, kFastExpRelTol);
    EXPECT_EQ(FastExp(-87.5f), 0.0f);
    EXPECT_EQ(FastExp(-1e30f), 0.0f);
    EXPECT_FLOAT_EQ(FastExp(0.0f), 1.0f);
}

// KernelRow works in pre-scaled coordinates: row[i] = 2^-|q - p_i|^2. Reference: std::exp2
// in double of the squared distance computed in double from the same float inputs; the
// tolerance is FastExp's polynomial bound plus float rounding of the argument (a few ulps
// of |d|^2, times ln 2).
TEST(KernelRow, MatchesStdExp2AndZeroesThePadding) {
    constexpr Eigen::Index kReal = 1000;
    const Eigen::Index count = (kReal + kKernelRowPad - 1) / kKernelRowPad * kKernelRowPad;
    std::vector<float> x(static_cast<size_t>(count), kKernelRowFar), y(x), z(x);
    auto rng = MakePairRng(7, 0);
    const PointCloud p = UniformBox(rng, kReal, {-8, -8, -8}, {8, 8, 8});
    for (Eigen::Index i = 0; i < kReal; ++i) {
        x[static_cast<size_t>(i)] = static_cast<float>(p(i, 0));
        y[static_cast<size_t>(i)] = static_cast<float>(p(i, 1));
        z[static_cast<size_t>(i)] = static_cast<float>(p(i, 2));
    }
    const Eigen::Vector3f q(0.5f, -0.25f, 1.0f);
    std::vector<float> row(static_cast<size_t>(count), -1.0f);
    const double sum = KernelRow({x.data(), y.data(), z.data(), count}, q, row.data());
    double ref_sum = 0.0;
    int underflowed = 0;
    for (Eigen::Index i = 0; i < kReal; ++i) {
        const auto k = static_cast<size_t>(i);
        const double d2 = std::pow(double{q.x()} - x[k], 2) + std::pow(double{q.y()} - y[k], 2) +
                          std::pow(double{q.z()} - z[k], 2);
        const double ref = std::exp2(-d2);
        if (d2 > 125.6) {  // FastExp's underflow point, -87 in base e
            EXPECT_EQ(row[k], 0.0f) << "d2 " << d2;
            ++underflowed;
            continue;
        }
        ref_sum += ref;
        EXPECT_NEAR(row[k], ref, ref * (kFastExpRelTol + 4 * 6e-8 * d2 * std::log(2.0)))
            << "d2 " << d2;
    }
    EXPECT_GT(underflowed, 0);  // the box reaches past the underflow radius
    for (Eigen::Index i = kReal; i < count; ++i) EXPECT_EQ(row[static_cast<size_t>(i)], 0.0f);
    EXPECT_NEAR(sum, ref_sum, kSumRelTol * ref_sum);
    EXPECT_THROW(KernelRow({x.data(), y.data(), z.data(), count - 1}, q, row.data()),
                 std::invalid_argument);
}

TEST(KernelSums, MatchesBruteForceWithWeightsAndMoments) {
    auto rng = MakePairRng(3, 0);
    const PointCloud q = UniformBox(rng, 300, {-1, -1, -1}, {1, 1, 1});
    const PointCloud p = UniformBox(rng, 500, {-1, -1, -1}, {1, 1, 1});
    const Eigen::Vector3d origin(0.3, -0.2, 0.1);
    const BlockedCloud bq(q, origin), bp(p, origin);
    std::vector<float> w(500);
    for (size_t j = 0; j < w.size(); ++j) w[j] = static_cast<float>(0.5 + 0.001 * j);
    for (double sigma2 : {1.0, 0.05, 1e-4}) {
        KernelSumResult out;
        KernelSums(bq, bp, sigma2, 1e30, w.data(), true, out);
        Eigen::VectorXd m0(300);
        PointCloud m1(300, 3);
        for (Eigen::Index i = 0; i < 300; ++i) {
            const Eigen::Index qi = bq.order()[static_cast<size_t>(i)];
            double s0 = 0.0;
            Eigen::RowVector3d s1 = Eigen::RowVector3d::Zero();
            for (Eigen::Index j = 0; j < 500; ++j) {
                const Eigen::Index pj = bp.order()[static_cast<size_t>(j)];
                const double k = w[static_cast<size_t>(j)] *
                                 std::exp(-(q.row(qi) - p.row(pj)).squaredNorm() / (2.0 * sigma2));
                s0 += k;
                s1 += k * (p.row(pj) - origin.transpose());
            }
            m0[i] = s0;
            m1.row(i) = s1;
        }
        EXPECT_LT(MaxRelDiff(out.m0, m0), kSumRelTol) << "sigma2 " << sigma2;
        EXPECT_LT(MaxRelDiff(out.m1, m1), kSumRelTol) << "sigma2 " << sigma2;
        if (sigma2 == 1e-4) {
            EXPECT_LT(out.evaluated_pairs, 300 * 500) << "pruning should skip far leaves";
        }
    }
}

TEST(GaussSumMode, JsonNamesRoundTrip) {
    // The JSON names are the `e_step` values users type (docs/probabilistic-baselines.md).
    EXPECT_EQ(nlohmann::json("dense").get<GaussSumMode>(), GaussSumMode::kDense);
    EXPECT_EQ(nlohmann::json("truncated").get<GaussSumMode>(), GaussSumMode::kTruncated);
    EXPECT_EQ(nlohmann::json("auto").get<GaussSumMode>(), GaussSumMode::kAuto);
    EXPECT_EQ(nlohmann::json(GaussSumMode::kTruncated), "truncated");
}

}  // namespace
}  // namespace regbench
