#include "core/metrics.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "core/transform.hpp"

namespace regbench {
namespace {

constexpr double kTol = 1e-9;

TEST(Metrics, RotationErrorsMatchHandComputation) {
    // R_gt = Rx(10) Ry(20) Rz(30) has scipy 'zyx' angles (30, 20, 10); R_est = Rx(16) Ry(20)
    // Rz(25) gives |dz| = 5, |dy| = 0, |dx| = 6: mae_r = 11/3, mse_r = (25 + 36) / 3.
    const Transform T_gt = MakeTransform(RotationXyzProductDeg(10, 20, 30), {0.1, 0.2, 0.3});
    const Transform T_est = MakeTransform(RotationXyzProductDeg(16, 20, 25), {0.1, 0.0, 0.0});
    const PairMetrics m = MotionMetrics(T_gt, T_est);
    EXPECT_EQ(m.euler, EulerConvention::kZyx);
    EXPECT_NEAR(m.mae_r, 11.0 / 3.0, kTol);
    EXPECT_NEAR(m.mse_r, 61.0 / 3.0, kTol);
    // The same angles as an Rz Ry Rx product are RPMNet's 'xyz' angles (10, 20, 30).
    const PairMetrics x =
        MotionMetrics(MakeTransform(RotationZyxProductDeg(30, 20, 10), Eigen::Vector3d::Zero()),
                      MakeTransform(RotationZyxProductDeg(25, 20, 16), Eigen::Vector3d::Zero()),
                      EulerConvention::kXyz);
    EXPECT_NEAR(x.mae_r, 11.0 / 3.0, kTol);
    EXPECT_NEAR(x.mse_r, 61.0 / 3.0, kTol);
    // t error (0, 0.2, 0.3): mae_t = 0.5 / 3, rte = sqrt(0.13), mse_t = 0.13 / 3.
    EXPECT_NEAR(m.mae_t, 0.5 / 3.0, kTol);
    EXPECT_NEAR(m.rte, std::sqrt(0.13), kTol);
    EXPECT_NEAR(m.mse_t, 0.13 / 3.0, kTol);
}

TEST(Metrics, RreOfKnownAxisAngle) {
    const Transform T_gt = Transform::Identity();
    const Transform T_est = MakeTransform(RotationFromAxisAngle({0, 0, 1}, 7.5 * M_PI / 180.0),
                                          Eigen::Vector3d::Zero());
    EXPECT_NEAR(MotionMetrics(T_gt, T_est).rre, 7.5, 1e-9);
    // About z only, the zyx angles differ in z alone: mae_r = 7.5 / 3.
    EXPECT_NEAR(MotionMetrics(T_gt, T_est).mae_r, 2.5, 1e-9);
}

TEST(Metrics, EulerDifferenceIsNotWrapped) {
    // z = 179 vs z = -179: the paper's metric takes |179 - (-179)| = 358, not 2.
    const Transform a = MakeTransform(RotationZyxProductDeg(179, 0, 0), Eigen::Vector3d::Zero());
    const Transform b = MakeTransform(RotationZyxProductDeg(-179, 0, 0), Eigen::Vector3d::Zero());
    EXPECT_NEAR(MotionMetrics(a, b).mae_r, 358.0 / 3.0, 1e-9);
    EXPECT_NEAR(MotionMetrics(a, b).rre, 2.0, 1e-9);
}

TEST(Metrics, ClippedChamferMatchesHandComputation) {
    // a = {(0,0,0), (1,0,0)}, b = {(0,0,0.05)}: a->b distances 0.05 and sqrt(1.0025) (clipped to
    // 0.1); b->a distance 0.05. ccd = (0.05 + 0.1) / 2 + 0.05 = 0.125.
    PointCloud a(2, 3);
    a << 0, 0, 0, 1, 0, 0;
    PointCloud b(1, 3);
    b << 0, 0, 0.05;
    const ChamferResult c = ChamferDistances(a, b);
    EXPECT_NEAR(c.ccd, 0.125, kTol);
    EXPECT_NEAR(c.chamfer, (0.0025 + 1.0025) / 2.0 + 0.0025, kTol);
    EXPECT_FALSE(c.within_clip);  // mean a->b distance ~0.53 > 0.1
}

TEST(Metrics, PerfectEstimateGivesZeroErrors) {
    PointCloud src(4, 3);
    src << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
    const Transform T = MakeTransform(RotationZyxProductDeg(40, -20, 10), {0.3, -0.1, 0.2});
    const PairMetrics m = ComputeMetrics(T, T, src, Apply(T, src));
    EXPECT_NEAR(m.mae_r, 0.0, 1e-9);
    EXPECT_NEAR(m.rre, 0.0, 1e-5);
    EXPECT_NEAR(m.ccd, 0.0, 1e-12);
    EXPECT_NEAR(m.chamfer, 0.0, 1e-12);
    EXPECT_TRUE(m.ccd_within_clip);
}

}  // namespace
}  // namespace regbench

namespace regbench {
namespace {

TEST(Metrics, ScaleIsDividedOutOfRotationErrors) {
    // A similarity estimate 1.3 * R_gt has the right rotation: rotation errors are zero.
    const Eigen::Matrix3d R = RotationZyxProductDeg(20, 10, 5);
    const Transform T_gt = MakeTransform(R, {0.1, 0.2, 0.3});
    const Transform T_est = MakeTransform(1.3 * R, {0.1, 0.2, 0.3});
    const PairMetrics m = MotionMetrics(T_gt, T_est);
    EXPECT_NEAR(m.mae_r, 0.0, 1e-9);
    EXPECT_NEAR(m.rre, 0.0, 1e-5);
}

}  // namespace
}  // namespace regbench

namespace regbench {
namespace {

Eigen::Matrix3d RowMajor(const std::array<double, 9>& m) {
    Eigen::Matrix3d R;
    R << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
    return R;
}

TEST(Metrics, MaeRMatchesScipyAsEulerForRandomRotations) {
    // Reference values from scipy 1.10.1 (/usr/bin/python3):
    //   rng = np.random.default_rng(5)
    //   for k in range(5):
    //     gt = Rotation.from_euler('zyx', rng.uniform(-45, 45, 3), degrees=True)
    //     est = Rotation.from_rotvec(rng.normal(size=3) * 0.3) * gt
    //     for seq in ('zyx', 'xyz'):
    //       d = abs(gt.as_euler(seq, degrees=True) - est.as_euler(seq, degrees=True))
    //       print(d.mean(), (d ** 2).mean())
    struct Case {
        std::array<double, 9> gt, est;
        double mae_zyx, mse_zyx, mae_xyz, mse_xyz;
    };
    const Case cases[] = {
        {{0.7856026834973072, -0.4080924991368504, 0.4650687431230672, 0.470779162966086,
          0.8819937000531687, -0.021309452913492274, -0.4014914736314846, 0.23568543700186628,
          0.885018062745873},
         {0.6002731759713288, -0.31503691885167795, 0.7351352623631487, 0.5561067398665608,
          0.8250076746075417, -0.10053671326257857, -0.5748194569465089, 0.46916316628556626,
          0.6704241309176026},
         8.998144083645329,
         145.16178501478046,
         14.455996614697332,
         224.78290753739302},
        {{0.7477698059411708, 0.10825372035791414, -0.6550736213215841, 0.31324268812940154,
          0.8123987065213136, 0.49182045501988103, 0.585422356641912, -0.5729655082735494,
          0.5735775367573793},
         {0.8039461673726835, 0.40462337518738023, -0.4358330921565567, -0.2664322264104645,
          0.9002537551412589, 0.34432113656298424, 0.531680758253236, -0.160695676998589,
          0.8315602628175718},
         17.22815545956222,
         299.1233389181137,
         26.270072858285932,
         952.7530290775439},
        {{0.7313546976404836, 0.07499405639519617, 0.6778614886129692, 0.3116227700576028,
          0.847363437046805, -0.4299609921119025, -0.6066395597229239, 0.5256910661801465,
          0.59635337470124},
         {0.75280381630667, 0.38641203163233495, 0.5328903789372489, -0.2792770991731345,
          0.9205819833608624, -0.2730075343077919, -0.5960626779387824, 0.05669703450051264,
          0.8009336615770966},
         16.253697785595662,
         284.0253860621452,
         27.179388449157404,
         1093.9222695458373},
        {{0.741799273091395, -0.2113356597835075, -0.6364519442541968, 0.21956281474041472,
          0.9732761336273763, -0.06727360622570706, 0.6336607995010769, -0.08983766813099471,
          0.768376980759081},
         {0.7470970166043868, -0.03612485509439466, -0.6637326590015243, -0.021011649574679124,
          0.9967397303421485, -0.07790006764831649, 0.6643828402080955, 0.07214502617554718,
          0.7439022360735005},
         5.388541336109367,
         59.225881150893066,
         10.873770895974694,
         160.65551164001204},
        {{0.8028463292941281, -0.2321295408432102, 0.5491390059054857, 0.03355441804774682,
          0.9372200601225367, 0.34712052652268516, -0.5952410205693335, -0.26025840077090606,
          0.7602326566648852},
         {0.9405762634891247, -0.08855047104440375, 0.3278339619970012, -0.04824490916541376,
          0.9207648700630058, 0.3871233431317173, -0.33613794980700706, -0.37993534731013195,
          0.8617774716038195},
         8.423231193932189,
         105.48353652507221,
         9.036964486115515,
         112.51833508559736},
    };
    for (const auto& c : cases) {
        const Transform gt = MakeTransform(RowMajor(c.gt), Eigen::Vector3d::Zero());
        const Transform est = MakeTransform(RowMajor(c.est), Eigen::Vector3d::Zero());
        const PairMetrics z = MotionMetrics(gt, est);  // default: the paper's 'zyx'
        EXPECT_NEAR(z.mae_r, c.mae_zyx, 1e-9);
        EXPECT_NEAR(z.mse_r, c.mse_zyx, 1e-8);
        const PairMetrics x = MotionMetrics(gt, est, EulerConvention::kXyz);
        EXPECT_NEAR(x.mae_r, c.mae_xyz, 1e-9);
        EXPECT_NEAR(x.mse_r, c.mse_xyz, 1e-8);
        EXPECT_EQ(x.euler, EulerConvention::kXyz);
        EXPECT_DOUBLE_EQ(z.rre, x.rre);  // the geodesic error does not depend on the convention
    }
}

}  // namespace
}  // namespace regbench

namespace regbench {
namespace {

// Issue 41 item 3: Open3D's evaluate_registration pair (fitness, inlier RMSE) at a threshold
// the user sets. Expected values from Open3D 0.16.1 (Debian's, /usr/bin/python3):
//   a, b = PointCloud(Vector3dVector(src)), PointCloud(Vector3dVector(tgt))
//   r = o3d.pipelines.registration.evaluate_registration(a, b, threshold, T)
//   threshold 0.3 -> fitness 0.875, inlier_rmse 0.18968461709614717 (7 correspondences)
//   threshold 0.15 -> 0.25, 0.08944271909999163; threshold 0.01 -> 0.0, 0.0
TEST(Metrics, FitnessAndInlierRmseMatchOpen3dEvaluateRegistration) {
    PointCloud src(8, 3), tgt(10, 3);
    src << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 0, 0.5, 0.5, 0.5, 2, 2, 2, -1, 0.5, 0.25;
    tgt << 0.1, 0, 0, 1.2, 0.1, 0, 0, 1, 0.25, 0.05, 0.05, 1.1, 3, 3, 3, 0.5, 0.4, 0.6, 1.0, 1.0,
        0.2, -0.9, 0.5, 0.5, 5, 5, 5, 0.2, 0.2, 0.2;
    Transform T = Transform::Identity();
    T.block<3, 3>(0, 0) << std::cos(0.1), -std::sin(0.1), 0, std::sin(0.1), std::cos(0.1), 0, 0, 0,
        1;
    T.block<3, 1>(0, 3) << 0.05, -0.02, 0.01;
    const struct {
        double threshold, fitness, rmse;
    } cases[] = {
        {0.3, 0.875, 0.18968461709614717}, {0.15, 0.25, 0.08944271909999163}, {0.01, 0.0, 0.0}};
    for (const auto& c : cases) {
        SCOPED_TRACE(c.threshold);
        MetricOptions o;
        o.inlier_threshold = c.threshold;
        const PairMetrics m =
            ComputeMetrics(Transform::Identity(), T, src, tgt, EulerConvention::kZyx, o);
        EXPECT_DOUBLE_EQ(m.fitness, c.fitness);
        EXPECT_NEAR(m.inlier_rmse, c.rmse, 1e-12);
        EXPECT_EQ(m.inlier_threshold, c.threshold);
    }
    // Not asked for: not computed (rows at the defaults keep their keys).
    EXPECT_TRUE(std::isnan(ComputeMetrics(Transform::Identity(), T, src, tgt).fitness));
}

// Issue 41 item 3: the CCD clip is a parameter; at the default the metric is the paper code's.
TEST(Metrics, CcdClipIsAnOptionAndScaleWarns) {
    PointCloud a(2, 3), b(2, 3);
    a << 0, 0, 0, 10, 0, 0;
    b << 0, 0, 3, 10, 0, 0.05;  // nearest distances 3 and 0.05 both ways
    MetricOptions wide;
    wide.ccd_clip = 5.0;
    // Hand derivation: default clip 0.1: mean(min(3, .1), .05) twice = 2 * 0.075 = 0.15;
    // clip 5: mean(3, 0.05) twice = 2 * 1.525 = 3.05.
    EXPECT_NEAR(ComputeMetrics(Transform::Identity(), Transform::Identity(), a, b).ccd, 0.15,
                1e-12);
    const PairMetrics m = ComputeMetrics(Transform::Identity(), Transform::Identity(), a, b,
                                         EulerConvention::kZyx, wide);
    EXPECT_NEAR(m.ccd, 3.05, 1e-12);
    EXPECT_EQ(m.ccd_clip, 5.0);
    // Millimetre-sized objects (radius 100) under the default clip: warned, with a clip to use.
    EXPECT_NE(ScaleWarning(100.0, MetricOptions{}).find("10% of the radius"), std::string::npos);
    EXPECT_NE(ScaleWarning(100.0, MetricOptions{}).find("e.g. 10,"), std::string::npos);
    EXPECT_EQ(ScaleWarning(1.0, MetricOptions{}), "");    // unit-sphere objects
    EXPECT_EQ(ScaleWarning(100.0, wide), "");             // the user chose a clip
    EXPECT_NE(ScaleWarning(0.001, MetricOptions{}), "");  // far below the clip
    PointCloud ring(4, 3);
    ring << 100, 0, 0, -100, 0, 0, 0, 100, 0, 0, -100, 0;
    EXPECT_NEAR(MedianCloudRadius({&ring}), 100.0, 1e-12);
}

}  // namespace
}  // namespace regbench
