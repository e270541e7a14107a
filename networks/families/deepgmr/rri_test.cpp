#include "networks/families/deepgmr/rri.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/transform.hpp"

namespace regbench::networks {
namespace {

// Expected values: /usr/bin/python3 with numpy + scipy.spatial.cKDTree, written from the RRI
// definition independently of networks/families/deepgmr/rri.cpp:
//   i = arange(12); P = stack([cos(.9i)(1+.05i), sin(.9i)(1+.03i), .15i-.4+.02i^2], 1)
//   k = 4; C = P - P.mean(0); idx = cKDTree(C).query(C, k+1)[1]
//   per point p = C[a], neighbours q = C[idx[a,1:]]: rp=|p|, ph=p/rp, rq=|q|,
//   d=clip(q.ph/rq,-1,1), th=arccos(d), T=q-d p, psi_jm=atan2(cross(T_j,T_m).ph, T_j.T_m)
//   (+2pi if < 0; numpy variant cross(T_m,T_j)), phi_j=min_m!=j psi_jm;
//   out[a, 4j..4j+3] = (rp, rq_j, th_j, phi_j)
PointCloud HelixPoints() {
    PointCloud p(12, 3);
    for (int i = 0; i < 12; ++i) {
        p.row(i) << std::cos(0.9 * i) * (1 + 0.05 * i), std::sin(0.9 * i) * (1 + 0.03 * i),
            0.15 * i - 0.4 + 0.02 * i * i;
    }
    return p;
}

const std::vector<double> kCudaRow0 = {
    1.9979187423393978, 1.7914281076158114, 0.4643149399035587, 1.8664485059041342,
    1.9979187423393978, 1.563543709586712,  0.9441076026180127, 0.454922594182433,
    1.9979187423393978, 1.4095252351419885, 1.1124721598772407, 3.0358432623202263,
    1.9979187423393978, 1.4886494866123772, 1.234296176416828,  0.8562867643780887};
const std::vector<double> kCudaRow7 = {
    1.4886494866123772, 1.4095252351419885, 0.8110272744294811, 0.0040289343977495074,
    1.4886494866123772, 1.4891228526542342, 0.8109054936764207, 2.865331399157214,
    1.4886494866123772, 1.9979187423393978, 1.234296176416828,  2.1666709630570087,
    1.4886494866123772, 1.3633403374588486, 1.6809618427993112, 1.246279086911238};
const std::vector<double> kNumpyRow0 = {
    1.9979187423393978, 1.7914281076158114, 0.4643149399035587, 0.454922594182433,
    1.9979187423393978, 1.563543709586712,  0.9441076026180127, 3.0358432623202263,
    1.9979187423393978, 1.4095252351419885, 1.1124721598772407, 0.8562867643780887,
    1.9979187423393978, 1.4886494866123772, 1.234296176416828,  1.8664485059041342};

void ExpectRow(const Eigen::MatrixXd& f, int row, const std::vector<double>& expected) {
    ASSERT_EQ(f.cols(), static_cast<Eigen::Index>(expected.size()));
    for (std::size_t c = 0; c < expected.size(); ++c) {
        EXPECT_NEAR(f(row, static_cast<Eigen::Index>(c)), expected[c], 1e-12) << "column " << c;
    }
}

TEST(Rri, MatchesNumpyReferenceCudaConvention) {
    const Eigen::MatrixXd f = RriFeatures(HelixPoints(), 4, RriVariant::kCuda);
    ExpectRow(f, 0, kCudaRow0);
    ExpectRow(f, 7, kCudaRow7);
}

TEST(Rri, NumpyVariantIsTheMirrorImage) {
    ExpectRow(RriFeatures(HelixPoints(), 4, RriVariant::kNumpy), 0, kNumpyRow0);
}

TEST(Rri, InvariantUnderRigidMotion) {
    const PointCloud p = HelixPoints();
    const Transform T = MakeTransform(RotationFromEulerZyxDeg(70, -35, 120), {0.3, -1.0, 2.0});
    const Eigen::MatrixXd a = RriFeatures(p, 4);
    const Eigen::MatrixXd b = RriFeatures(Apply(T, p), 4);
    EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Rri, TensorLayoutIsBatchChannelsPoints) {
    const PointCloud p = HelixPoints();
    torch::Tensor xyz = torch::empty({2, 12, 3}, torch::kFloat);
    for (int b = 0; b < 2; ++b) {
        for (int i = 0; i < 12; ++i) {
            for (int c = 0; c < 3; ++c) xyz[b][i][c] = static_cast<float>(p(i, c));
        }
    }
    const torch::Tensor f = RriFeatureTensor(xyz, 4, RriVariant::kCuda);
    ASSERT_EQ(f.sizes(), (std::vector<int64_t>{2, 16, 12}));
    for (int c = 0; c < 16; ++c) EXPECT_NEAR(f[1][c][7].item<float>(), kCudaRow7[c], 1e-5);
}

TEST(Rri, RejectsTooFewPoints) {
    EXPECT_THROW(RriFeatures(HelixPoints().topRows(4), 4), std::invalid_argument);
}

}  // namespace
}  // namespace regbench::networks
