#include "datasets/indoor_sim.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <stdexcept>
#include <string>

#include "core/kd_tree.hpp"
#include "core/math_constants.hpp"
#include "core/rng.hpp"
#include "core/transform.hpp"
#include "datasets/ray_caster.hpp"

namespace regbench {
namespace {

/// A square of side 2 * half_side in the plane z = depth (world frame), two triangles.
Mesh Quad(double depth, double half_side) {
    Mesh mesh;
    mesh.vertices.resize(4, 3);
    mesh.vertices << -half_side, -half_side, depth, half_side, -half_side, depth, half_side,
        half_side, depth, -half_side, half_side, depth;
    mesh.faces.resize(2, 3);
    mesh.faces << 0, 1, 2, 0, 2, 3;
    return mesh;
}

/// Small images keep every test fast; the focal length keeps the default field of view.
IndoorSimOptions SmallCamera(int width, int height) {
    IndoorSimOptions o;
    o.image_width = width;
    o.image_height = height;
    o.fx = o.fy = 525.0 * width / 640.0;
    o.cx = 0.5 * (width - 1);
    o.cy = 0.5 * (height - 1);
    return o;
}

std::string MeshDir() {
    const char* root = std::getenv("REGBENCH_SOURCE_DIR");
    return std::string(root ? root : ".") + "/data/meshes";
}

const FurnitureLibrary& Library() {
    static const FurnitureLibrary library = LoadFurnitureMeshes(MeshDir());
    return library;
}

TEST(RayCaster, HitsPlaneAtExactDistanceAndMisses) {
    const RayCaster scene(Quad(2.0, 10.0));
    const RayHit straight = scene.CastRay(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 3));
    ASSERT_TRUE(straight.hit);
    EXPECT_NEAR(straight.distance, 2.0, 1e-12);
    EXPECT_NEAR(std::abs(straight.normal.z()), 1.0, 1e-12);
    const RayHit oblique = scene.CastRay(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 0, 1));
    ASSERT_TRUE(oblique.hit);
    EXPECT_NEAR(oblique.distance, 2.0 * std::sqrt(2.0), 1e-12);
    EXPECT_FALSE(scene.CastRay(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -1)).hit);
    EXPECT_FALSE(scene.CastRay(Eigen::Vector3d::Zero(), Eigen::Vector3d(20, 0, 1)).hit);
}

TEST(RayCaster, RejectsMeshWithoutTriangles) {
    Mesh degenerate = Quad(1.0, 1.0);
    degenerate.faces << 0, 0, 1, 2, 2, 3;
    EXPECT_THROW(RayCaster{degenerate}, std::invalid_argument);
}

TEST(IndoorSim, RenderOfFrontoParallelPlaneHasExactDepth) {
    const IndoorSimOptions o = SmallCamera(64, 48);
    const RayCaster scene(Quad(2.0, 10.0));
    const DepthRender render = RenderDepth(scene, o, Transform::Identity());
    ASSERT_EQ(render.depth.size(), 64 * 48);
    for (Eigen::Index i = 0; i < render.depth.size(); ++i) {
        ASSERT_NEAR(render.depth[i], 2.0, 1e-12) << "pixel " << i;
    }
    // Noise off: back-projected points lie on the plane at their pixel's ray.
    IndoorSimOptions exact = o;
    exact.noise = false;
    std::mt19937_64 rng(1);
    const IndoorScan scan = ScanFromRender(render, exact, Transform::Identity(), rng);
    ASSERT_EQ(scan.points_camera.rows(), 64 * 48);
    EXPECT_NEAR(scan.points_camera.col(2).maxCoeff(), 2.0, 1e-12);
    EXPECT_NEAR(scan.points_camera.col(2).minCoeff(), 2.0, 1e-12);
    EXPECT_NEAR(scan.points_camera(0, 0), (0 - o.cx) / o.fx * 2.0, 1e-12);
}

TEST(IndoorSim, AxialNoiseMatchesNguyenModel) {
    IndoorSimOptions o = SmallCamera(160, 120);
    o.disparity_subpixel = 0;  // Gaussian part alone
    const double depth = 3.0;
    const RayCaster scene(Quad(depth, 20.0));
    const DepthRender render = RenderDepth(scene, o, Transform::Identity());
    std::mt19937_64 rng(7);
    const IndoorScan scan = ScanFromRender(render, o, Transform::Identity(), rng);
    ASSERT_EQ(scan.points_camera.rows(), 160 * 120);
    // Normalised residuals (z - depth) / sigma_z(depth, theta) are standard normal.
    double sum = 0.0;
    double sum_sq = 0.0;
    for (Eigen::Index k = 0; k < scan.points_camera.rows(); ++k) {
        const double theta = render.incidence[scan.pixel[k]];
        const double r = (scan.points_camera(k, 2) - depth) / KinectAxialSigma(o, depth, theta);
        sum += r;
        sum_sq += r * r;
    }
    const double n = static_cast<double>(scan.points_camera.rows());
    const double mean = sum / n;
    const double std_dev = std::sqrt(sum_sq / n - mean * mean);
    constexpr double kStdTolerance = 0.03;  // ~10 standard errors for 19200 samples
    EXPECT_NEAR(mean, 0.0, kStdTolerance);
    EXPECT_NEAR(std_dev, 1.0, kStdTolerance);
    // Model value at 3 m, frontal: 0.0012 + 0.0019 * 2.6^2.
    EXPECT_NEAR(KinectAxialSigma(o, depth, 0.0), 0.0012 + 0.0019 * 2.6 * 2.6, 1e-15);
}

TEST(IndoorSim, DisparityQuantisationSnapsToLevels) {
    IndoorSimOptions o;
    const double fb = o.sensor_focal_px * o.stereo_baseline_m;
    for (double z : {0.7, 1.3, 2.0, 3.1, 3.9}) {
        const double q = QuantiseDepth(o, z);
        const double level = fb / q * o.disparity_subpixel;
        EXPECT_NEAR(level, std::round(level), 1e-9) << z;
        // Half a disparity step: |dz| <= z^2 / (f b) / (2 * subpixel), to first order.
        EXPECT_LE(std::abs(q - z), 1.01 * z * z / fb / (2.0 * o.disparity_subpixel)) << z;
    }
    o.disparity_subpixel = 0;
    EXPECT_EQ(QuantiseDepth(o, 2.345), 2.345);
}

TEST(IndoorSim, GrazingReturnsAreDropped) {
    // Camera 1 m above an infinite floor, looking horizontally: rays near the horizon graze.
    IndoorSimOptions o = SmallCamera(64, 48);
    o.noise = false;
    o.max_range_m = 1000.0;  // the floor ends 200 m away: nothing is out of range
    Mesh floor = Quad(0.0, 200.0);
    const RayCaster scene(floor);
    const Transform T_world_camera =
        LookAt(Eigen::Vector3d(0.0, 0.0, 1.0), Eigen::Vector3d(1.0, 0.0, 1.0));
    const DepthRender render = RenderDepth(scene, o, T_world_camera);
    int grazing = 0;
    for (Eigen::Index i = 0; i < render.depth.size(); ++i) {
        if (render.depth[i] > 0.0 && render.incidence[i] > 75.0 * kPi / 180.0) ++grazing;
    }
    ASSERT_GT(grazing, 0);
    std::mt19937_64 rng(3);
    const IndoorScan kept = ScanFromRender(render, o, T_world_camera, rng);
    for (Eigen::Index k = 0; k < kept.pixel.size(); ++k) {
        EXPECT_LE(render.incidence[kept.pixel[k]], 75.0 * kPi / 180.0);
    }
    IndoorSimOptions all = o;
    all.max_incidence_deg = 90.0;
    const IndoorScan everything = ScanFromRender(render, all, T_world_camera, rng);
    EXPECT_EQ(everything.pixel.size() - kept.pixel.size(), grazing);
    // Points of the floor are on the floor in the world frame.
    EXPECT_NEAR(everything.points_world.col(2).cwiseAbs().maxCoeff(), 0.0, 1e-9);
}

TEST(IndoorSim, RangeLimitsDropReturns) {
    IndoorSimOptions o = SmallCamera(32, 24);
    o.noise = false;
    const RayCaster scene(Quad(5.0, 50.0));
    std::mt19937_64 rng(5);
    EXPECT_EQ(SimulateScan(scene, o, Transform::Identity(), rng).points_camera.rows(), 0);
    o.max_range_m = 6.0;
    EXPECT_EQ(SimulateScan(scene, o, Transform::Identity(), rng).points_camera.rows(), 32 * 24);
    o.min_range_m = 5.5;
    EXPECT_EQ(SimulateScan(scene, o, Transform::Identity(), rng).points_camera.rows(), 0);
}

TEST(IndoorSim, LookAtGivesRightHandedDownwardCamera) {
    const Eigen::Vector3d eye(1.0, 2.0, 1.5);
    const Eigen::Vector3d target(3.0, 2.5, 0.5);
    const Transform T = LookAt(eye, target);
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    EXPECT_TRUE(IsRotation(R));
    EXPECT_TRUE(R.col(2).isApprox((target - eye).normalized(), 1e-12));
    EXPECT_LT(R.col(1).z(), 0.0);           // image y points down in the world
    EXPECT_NEAR(R.col(0).z(), 0.0, 1e-12);  // no roll
    EXPECT_THROW(LookAt(eye, eye + Eigen::Vector3d(0, 0, 1)), std::invalid_argument);
}

TEST(IndoorSim, FurnitureLibraryHoldsUsableMeshes) {
    const FurnitureLibrary& library = Library();
    ASSERT_GE(library.meshes.size(), 10u);
    ASSERT_EQ(library.names.size(), library.meshes.size());
    for (std::size_t i = 1; i < library.names.size(); ++i) {
        // Sorted by file name, so draws do not depend on directory order.
        EXPECT_LT(library.names[i - 1] + ".off", library.names[i] + ".off");
    }
    for (const auto& mesh : library.meshes) {
        EXPECT_GE(mesh.faces.rows(), 100);
        EXPECT_LE(mesh.faces.rows(), 20000);
    }
    EXPECT_THROW(LoadFurnitureMeshes(MeshDir() + "/no_such_dir"), std::runtime_error);
}

TEST(IndoorSim, RoomObjectsStandInsideTheRoomWithoutOverlap) {
    const IndoorSimOptions o;
    int on_boxes = 0;
    for (std::uint64_t k = 0; k < 10; ++k) {
        std::mt19937_64 rng = MakePairRng(11, k);
        const IndoorRoom room = AssembleRoom(o, Library(), rng);
        ASSERT_GE(room.objects.size(), 1u);
        const Eigen::RowVector3d lo = room.mesh.vertices.colwise().minCoeff();
        const Eigen::RowVector3d hi = room.mesh.vertices.colwise().maxCoeff();
        EXPECT_NEAR(lo.norm(), 0.0, 1e-9);
        EXPECT_TRUE(hi.transpose().isApprox(room.size_m, 1e-9));
        for (std::size_t i = 0; i < room.objects.size(); ++i) {
            const auto& a = room.objects[i];
            EXPECT_GE(a.centre_xy.minCoeff() - a.radius_m, o.object_wall_margin_m - 1e-9);
            if (a.support >= 0) {  // on a table top: inside the box's inscribed circle
                const auto& box = room.objects[static_cast<std::size_t>(a.support)];
                EXPECT_EQ(box.name, "box");
                EXPECT_TRUE(a.centre_xy.isApprox(box.centre_xy));
                EXPECT_GT(a.height_m, box.height_m);
                ++on_boxes;
                continue;
            }
            for (std::size_t j = i + 1; j < room.objects.size(); ++j) {
                const auto& b = room.objects[j];
                if (b.support >= 0) continue;
                EXPECT_GE((a.centre_xy - b.centre_xy).norm(), a.radius_m + b.radius_m - 1e-9);
            }
        }
    }
    EXPECT_GT(on_boxes, 0);  // some meshes stand on table tops
}

/// Options for the pair tests: a 160 x 120 image (fast) with proportionally fewer points.
IndoorSimOptions PairOptions() {
    IndoorSimOptions o = SmallCamera(160, 120);
    o.min_valid_points = 2048;
    return o;
}

TEST(IndoorSim, TwoViewsOverlapAfterGroundTruth) {
    IndoorSimOptions o = PairOptions();
    o.noise = false;
    std::mt19937_64 rng = MakePairRng(2023, 0);
    const IndoorScanPair pair = SimulateIndoorPair(o, Library(), rng);
    ASSERT_GE(pair.a.points_camera.rows(), o.min_valid_points);
    ASSERT_GE(pair.b.points_camera.rows(), o.min_valid_points);
    EXPECT_TRUE(pair.T_b_a.isApprox(
        Compose(InvertRigid(pair.b.T_world_camera), pair.a.T_world_camera), 1e-12));

    // Points of A that B sees too (B has a return at their pixel with the same depth) lie on
    // B's scan after T_gt, up to the pixel footprint.
    std::map<int, Eigen::Index> b_at_pixel;
    for (Eigen::Index k = 0; k < pair.b.pixel.size(); ++k) b_at_pixel[pair.b.pixel[k]] = k;
    const PointCloud a_in_b = Apply(pair.T_b_a, pair.a.points_camera);
    const KdTree b_tree(pair.b.points_camera);
    int covisible = 0;
    int close = 0;
    for (Eigen::Index k = 0; k < a_in_b.rows(); ++k) {
        const Eigen::Vector3d p = a_in_b.row(k).transpose();
        if (p.z() <= 0.0) continue;
        const int u = static_cast<int>(std::lround(o.fx * p.x() / p.z() + o.cx));
        const int v = static_cast<int>(std::lround(o.fy * p.y() / p.z() + o.cy));
        if (u < 0 || v < 0 || u >= o.image_width || v >= o.image_height) continue;
        const auto it = b_at_pixel.find(v * o.image_width + u);
        if (it == b_at_pixel.end()) continue;
        if (std::abs(pair.b.points_camera(it->second, 2) - p.z()) > 0.02) continue;  // occluded
        ++covisible;
        // Pixel footprint at 4 m and 160 px: 4 / 131 = 3 cm; a diagonal neighbour is closer.
        if (std::sqrt(b_tree.Nearest(p).second) < 0.03) ++close;
    }
    EXPECT_GT(covisible, a_in_b.rows() / 5);
    EXPECT_GE(close, 0.99 * covisible);
    EXPECT_GT(pair.a_overlap_ratio, 0.2);
    EXPECT_GT(pair.b_overlap_ratio, 0.2);
    // The labels are what OverlapLabels computes.
    EXPECT_EQ(pair.a_overlap, OverlapLabels(pair.a.points_camera, pair.b.points_camera, pair.T_b_a,
                                            o.overlap_eta_m));
    // A wrong ground truth (15 degrees and 35 cm off) destroys most of the overlap. (A pure
    // shift can slide walls and floor along themselves and keep them overlapping.)
    const Transform error =
        MakeTransform(RotationFromAxisAngle(Eigen::Vector3d(1, 1, 1), 15.0 * kPi / 180.0),
                      Eigen::Vector3d::Constant(0.2));
    const Transform wrong = Compose(error, pair.T_b_a);
    const auto wrong_labels =
        OverlapLabels(pair.a.points_camera, pair.b.points_camera, wrong, o.overlap_eta_m);
    EXPECT_LT(wrong_labels.cast<double>().mean(), 0.5 * pair.a_overlap_ratio);
}

TEST(IndoorSim, SameSeedGivesBitwiseSamePair) {
    const IndoorSimOptions o = PairOptions();
    std::mt19937_64 rng1 = MakePairRng(99, 4);
    std::mt19937_64 rng2 = MakePairRng(99, 4);
    std::mt19937_64 rng3 = MakePairRng(99, 5);
    const IndoorScanPair p1 = SimulateIndoorPair(o, Library(), rng1);
    const IndoorScanPair p2 = SimulateIndoorPair(o, Library(), rng2);
    const IndoorScanPair p3 = SimulateIndoorPair(o, Library(), rng3);
    ASSERT_EQ(p1.a.points_camera.rows(), p2.a.points_camera.rows());
    ASSERT_EQ(p1.b.points_camera.rows(), p2.b.points_camera.rows());
    EXPECT_TRUE((p1.a.points_camera.array() == p2.a.points_camera.array()).all());
    EXPECT_TRUE((p1.b.points_camera.array() == p2.b.points_camera.array()).all());
    EXPECT_TRUE((p1.T_b_a.array() == p2.T_b_a.array()).all());
    EXPECT_EQ(p1.name, p2.name);
    EXPECT_FALSE(p1.a.points_camera.rows() == p3.a.points_camera.rows() &&
                 (p1.a.points_camera.array() == p3.a.points_camera.array()).all());
}

TEST(IndoorSim, RenderIsIndependentOfThreadCount) {
    const IndoorSimOptions o = PairOptions();
    std::mt19937_64 rng = MakePairRng(8, 0);
    const IndoorRoom room = AssembleRoom(o, Library(), rng);
    const RayCaster scene(room.mesh);
    const Transform T = LookAt(Eigen::Vector3d(0.5, 0.5, 1.5), Eigen::Vector3d(2.5, 2.0, 0.5));
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    const DepthRender one = RenderDepth(scene, o, T);
    omp_set_num_threads(3);
    const DepthRender three = RenderDepth(scene, o, T);
    omp_set_num_threads(threads);
    EXPECT_TRUE((one.depth.array() == three.depth.array()).all());
    EXPECT_TRUE((one.incidence.array() == three.incidence.array()).all());
    EXPECT_GT((one.depth.array() > 0.0).count(), one.depth.size() / 2);
}

TEST(IndoorSim, SingleScanIsReproducibleAndInMetres) {
    const IndoorSimOptions o = PairOptions();
    std::mt19937_64 rng1 = MakePairRng(5, 1);
    std::mt19937_64 rng2 = MakePairRng(5, 1);
    const IndoorScan s1 = SimulateIndoorScan(o, Library(), rng1);
    const IndoorScan s2 = SimulateIndoorScan(o, Library(), rng2);
    ASSERT_GE(s1.points_camera.rows(), o.min_valid_points);
    EXPECT_TRUE((s1.points_camera.array() == s2.points_camera.array()).all());
    // Raw camera-frame metres: depths within the sensor range (plus noise and quantisation).
    EXPECT_GT(s1.points_camera.col(2).minCoeff(), o.min_range_m - 0.05);
    EXPECT_LT(s1.points_camera.col(2).maxCoeff(), o.max_range_m + 0.2);
}

TEST(IndoorSim, OptionsRejectUnknownAndInconsistentValues) {
    EXPECT_NO_THROW(ParseIndoorSimOptions(nlohmann::json::object()));
    EXPECT_THROW(ParseIndoorSimOptions({{"sigma", 1.0}}), std::invalid_argument);
    EXPECT_THROW(ParseIndoorSimOptions({{"max_range_m", 0.1}}), std::invalid_argument);
    EXPECT_THROW(ParseIndoorSimOptions({{"max_incidence_deg", 120.0}}), std::invalid_argument);
    const IndoorSimOptions o = ParseIndoorSimOptions({{"image_width", 80}, {"noise", false}});
    EXPECT_EQ(o.image_width, 80);
    EXPECT_FALSE(o.noise);
}

}  // namespace
}  // namespace regbench
