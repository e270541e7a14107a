#include "core/transform.hpp"

#include <gtest/gtest.h>

#include <random>

#include "core/rng.hpp"

namespace regbench {
namespace {

constexpr double kTol = 1e-12;

TEST(Transform, ZyxProductMatchesScipyIntrinsicZyx) {
    // Rz(90) maps x to y: R.from_euler('ZYX', [90, 0, 0], degrees=True).
    const Eigen::Matrix3d R = RotationZyxProductDeg(90.0, 0.0, 0.0);
    EXPECT_NEAR(R(0, 0), 0.0, kTol);
    EXPECT_NEAR(R(1, 0), 1.0, kTol);
    EXPECT_NEAR(R(0, 1), -1.0, kTol);
    // Rz(30) Ry(20) Rx(10) is scipy's *upper-case* (intrinsic) sequence:
    // Rotation.from_euler('ZYX', [30, 20, 10], degrees=True).as_matrix()
    const Eigen::Matrix3d Q = RotationZyxProductDeg(30.0, 20.0, 10.0);
    EXPECT_NEAR(Q(0, 0), 0.81379768, 1e-8);
    EXPECT_NEAR(Q(0, 1), -0.44096961, 1e-8);
    EXPECT_NEAR(Q(0, 2), 0.37852231, 1e-8);
    EXPECT_NEAR(Q(1, 0), 0.46984631, 1e-8);
    EXPECT_NEAR(Q(1, 1), 0.88256412, 1e-8);
    EXPECT_NEAR(Q(1, 2), 0.01802831, 1e-8);
    EXPECT_NEAR(Q(2, 0), -0.34202014, 1e-8);
    EXPECT_NEAR(Q(2, 1), 0.16317591, 1e-8);
    EXPECT_NEAR(Q(2, 2), 0.92541658, 1e-8);
}

/// A rotation matrix (row-major) with the angles scipy returns for it.
struct EulerCase {
    double m[9];
    double zyx[3];  ///< Rotation.from_matrix(m).as_euler('zyx', degrees=True)
    double xyz[3];  ///< Rotation.from_matrix(m).as_euler('xyz', degrees=True)
};

// Computed with scipy 1.10.1 (/usr/bin/python3, Debian 12):
//   rs = list(Rotation.random(5, random_state=2023).as_matrix())
//   rs.append(Rotation.from_euler('zyx', [30, 89.99, -40], degrees=True).as_matrix())
//   rs.append(Rotation.from_euler('xyz', [-120, -89.99, 75], degrees=True).as_matrix())
//   for R in rs: print(R.ravel(), Rotation.from_matrix(R).as_euler('zyx', degrees=True),
//                      Rotation.from_matrix(R).as_euler('xyz', degrees=True))
// The last two are 0.01 deg from gimbal lock of the respective convention.
const EulerCase kScipyCases[] = {
    {{-0.32712987083188766, 0.006899156269426776, -0.944954204843961, -0.5595787687346934,
      -0.807213382125789, 0.18782480480066935, -0.7614838469664849, 0.5902194145907225,
      0.2679242307991347},
     {-178.79181334267332, -70.90092676983257, -35.03187793261922},
     {65.58479930560102, 49.59518575683689, -120.31056563448342}},
    {{-0.6002034438024504, -0.7106162857658299, -0.3671243937033537, 0.755313224060065,
      -0.35253493228123456, -0.5524681484768651, 0.2631686904015539, -0.6088871947461546,
      0.7483305582872382},
     {130.18523286734603, -21.538380134874135, 36.43724765087533},
     {-39.13389587138561, -15.258164436025712, 128.47212111597042}},
    {{-0.9789720623949878, -0.11967465526825367, 0.16520193078934933, 0.007601080618284586,
      0.7878734851357538, 0.6157902199560136, -0.20385270325295826, 0.6040971348272278,
      -0.7703964739470162},
     {173.0304449733753, 9.508965235703094, -141.3640966165377},
     {141.89865805453667, 11.762345633612016, 179.55514451880182}},
    {{0.03989817534877185, -0.07397243901360828, 0.9964618476741678, 0.7568517633385989,
      -0.6488586175319869, -0.07847230585201337, 0.6523676447641251, 0.7573048083307384,
      0.03009789600705351},
     {61.659111514920404, 85.17881244792528, 69.01578361620915},
     {87.72406659701842, -40.72035091354287, 86.98239058548064}},
    {{-0.7529609488997893, 0.41985859428694683, 0.506723366577187, -0.3430449120422965,
      -0.9075491669753748, 0.24222860657692052, 0.5615781314775551, 0.008559808741584393,
      0.8273794364863594},
     {-150.85552309153698, 30.445820242874305, -16.318238960944505},
     {0.5927430583861469, -34.1650064563926, -155.50624829914435}},
    {{0.00015114994625187173, -8.726646215667655e-05, 0.999999984769129, -0.1736481691883553,
      0.9848077481171004, 0.00011218760123095362, -0.9848077429078357, -0.17364818350069233,
      0.00013369997681134116},
     {30.000000000045766, 89.99000000009023, -40.00000000003334},
     {-89.95588526914534, 79.99999666603023, -89.95012759508403}},
    {{4.517244480967131e-05, 0.707106777772641, -0.7071067831575673, 0.0001685858591317646,
      0.7071067684456758, 0.7071067738306016, 0.999999984769129, -0.00015114994625192724,
      -8.726646215656553e-05},
     {-89.99633974596806, -45.000000159708726, -90.0070710678136},
     {-120.0000000000391, -89.99000000001735, 75.00000000003267}},
};

Eigen::Matrix3d MatrixOf(const double (&m)[9]) {
    Eigen::Matrix3d R;
    R << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
    return R;
}

TEST(Transform, EulerAnglesMatchScipyForRandomAndNearGimbalRotations) {
    // scipy's own decomposition near gimbal lock is accurate to ~1e-7 deg only.
    constexpr double kDegTol = 1e-6;
    for (const auto& c : kScipyCases) {
        const Eigen::Matrix3d R = MatrixOf(c.m);
        const Eigen::Vector3d zyx = EulerZyxDegFromRotation(R);
        const Eigen::Vector3d xyz = EulerXyzDegFromRotation(R);
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(zyx[k], c.zyx[k], kDegTol) << "zyx angle " << k << " of " << R;
            EXPECT_NEAR(xyz[k], c.xyz[k], kDegTol) << "xyz angle " << k << " of " << R;
        }
        EXPECT_EQ(EulerDegFromRotation(R, EulerConvention::kZyx), zyx);
        EXPECT_EQ(EulerDegFromRotation(R, EulerConvention::kXyz), xyz);
    }
}

TEST(Transform, EulerAnglesAtExactGimbalLockMatchScipy) {
    // scipy sets the last angle to 0 at gimbal lock and folds the rest into the first:
    //   R = Rotation.from_euler('zyx', [30, 90, -40], degrees=True)
    //   R.as_euler('zyx', degrees=True) -> [-10, 90, 0]
    //   Rotation.from_euler('xyz', [30, 90, -40], degrees=True).as_euler('xyz', ...) -> [70, 90, 0]
    //   Rotation.from_euler('xyz', [10, -90, 60], degrees=True).as_euler('xyz', ...) -> [70, -90,
    //   0] Rotation.from_euler('zyx', [-50, -90, 20], degrees=True).as_euler('zyx', ...) -> [-70,
    //   -90, 0]
    constexpr double kDegTol = 1e-5;  // scipy returns -90.00000121 for the last one
    const auto expect = [&](const Eigen::Vector3d& got, double a, double b, double c) {
        EXPECT_NEAR(got[0], a, kDegTol) << got.transpose();
        EXPECT_NEAR(got[1], b, kDegTol) << got.transpose();
        EXPECT_NEAR(got[2], c, kDegTol) << got.transpose();
    };
    // from_euler('zyx', [z, y, x]) is Rx(x) Ry(y) Rz(z); from_euler('xyz', [x, y, z]) is
    // Rz(z) Ry(y) Rx(x) = RotationZyxProductDeg(z, y, x).
    expect(EulerZyxDegFromRotation(RotationXyzProductDeg(-40, 90, 30)), -10, 90, 0);
    expect(EulerZyxDegFromRotation(RotationXyzProductDeg(20, -90, -50)), -70, -90, 0);
    expect(EulerXyzDegFromRotation(RotationZyxProductDeg(-40, 90, 30)), 70, 90, 0);
    expect(EulerXyzDegFromRotation(RotationZyxProductDeg(60, -90, 10)), 70, -90, 0);
}

TEST(Transform, PaperMotionDecomposesIntoItsOwnAnglesUnderZyx) {
    // The protocol draws R = Rx(x) Ry(y) Rz(z); scipy's extrinsic 'zyx' returns (z, y, x) for
    // it (hand derivation: first row (cos y cos z, -cos y sin z, sin y)), and 'xyz' returns
    // (x, y, z) for Rz(z) Ry(y) Rx(x).
    std::mt19937_64 rng(7);
    for (int i = 0; i < 100; ++i) {
        const double z = UniformReal(rng, -179.0, 179.0);
        const double y = UniformReal(rng, -89.0, 89.0);
        const double x = UniformReal(rng, -179.0, 179.0);
        const Eigen::Vector3d e = EulerZyxDegFromRotation(RotationXyzProductDeg(x, y, z));
        EXPECT_NEAR(e[0], z, 1e-9);
        EXPECT_NEAR(e[1], y, 1e-9);
        EXPECT_NEAR(e[2], x, 1e-9);
        const Eigen::Vector3d f = EulerXyzDegFromRotation(RotationZyxProductDeg(z, y, x));
        EXPECT_NEAR(f[0], x, 1e-9);
        EXPECT_NEAR(f[1], y, 1e-9);
        EXPECT_NEAR(f[2], z, 1e-9);
    }
}

TEST(Transform, EulerConventionNames) {
    EXPECT_EQ(ParseEulerConvention("zyx"), EulerConvention::kZyx);
    EXPECT_EQ(ParseEulerConvention("xyz"), EulerConvention::kXyz);
    EXPECT_STREQ(ToString(EulerConvention::kZyx), "zyx");
    EXPECT_STREQ(ToString(EulerConvention::kXyz), "xyz");
    EXPECT_THROW(ParseEulerConvention("ZYX"), std::invalid_argument);
}

TEST(Transform, PaperMotionIsXyzProduct) {
    const Eigen::Matrix3d R = RotationXyzProductDeg(10.0, 20.0, 30.0);
    const Eigen::Matrix3d expected =
        RotationFromAxisAngle(Eigen::Vector3d::UnitX(), 10.0 * M_PI / 180.0) *
        RotationFromAxisAngle(Eigen::Vector3d::UnitY(), 20.0 * M_PI / 180.0) *
        RotationFromAxisAngle(Eigen::Vector3d::UnitZ(), 30.0 * M_PI / 180.0);
    EXPECT_LT((R - expected).cwiseAbs().maxCoeff(), kTol);
}

TEST(Transform, InvertComposeApply) {
    const Transform T = MakeTransform(RotationZyxProductDeg(10, 20, 30), {0.1, -0.2, 0.3});
    EXPECT_LT((Compose(T, InvertRigid(T)) - Transform::Identity()).cwiseAbs().maxCoeff(), kTol);
    PointCloud p(2, 3);
    p << 1, 0, 0, 0, 1, 0;
    const PointCloud q = Apply(T, p);
    const Eigen::Vector3d q0 =
        T.topLeftCorner<3, 3>() * Eigen::Vector3d(1, 0, 0) + T.topRightCorner<3, 1>();
    EXPECT_LT((q.row(0).transpose() - q0).norm(), kTol);
    EXPECT_LT((Apply(InvertRigid(T), q) - p).cwiseAbs().maxCoeff(), kTol);
}

TEST(Transform, RotationAngleOfKnownRotation) {
    const Eigen::Matrix3d R = RotationFromAxisAngle({1, 1, 0}, 0.5);
    EXPECT_NEAR(RotationAngleDeg(Eigen::Matrix3d::Identity(), R), 0.5 * 180.0 / M_PI, 1e-9);
    EXPECT_TRUE(IsRotation(R));
    EXPECT_FALSE(IsRotation(2.0 * R));
    EXPECT_FALSE(IsRotation(-R));
}

TEST(Rng, PairStreamDependsOnlyOnSeedAndIndex) {
    auto a = MakePairRng(42, 17);
    auto b = MakePairRng(42, 17);
    auto c = MakePairRng(42, 18);
    auto d = MakePairRng(43, 17);
    const auto va = a();
    EXPECT_EQ(va, b());
    EXPECT_NE(va, c());
    EXPECT_NE(va, d());
}

}  // namespace
}  // namespace regbench
