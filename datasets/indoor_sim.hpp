#pragma once
// Simulated indoor depth scans, standing in for 7Scenes / ICL-NUIM (paper Tab. 3) when those
// datasets are not on the machine (docs/indoor-simulation.md).
//
// A room is a closed box (floor, ceiling, four walls) with furniture-like boxes and meshes from
// the embedded corpus standing on the floor. A Kinect-like pinhole depth camera renders it by
// ray casting (datasets/ray_caster.hpp, CGAL), then the depth is corrupted with the noise
// model of Nguyen, Izadi and Lovell, "Modeling Kinect Sensor Noise for Improved 3D
// Reconstruction and Tracking", 3DIMPVT 2012, quantised in disparity, and back-projected.
// Two nearby camera poses give a pair whose overlap comes from visibility.
//
// Frames and units: metres throughout. World: z up, floor at z = 0, room spans
// [0, width] x [0, depth] x [0, height]. Camera: OpenCV axes (x right, y down, z forward);
// points_camera are raw metres in the camera frame, NOT centred or scaled (the paper feeds raw
// 7Scenes metres to its resampling and 70% crop).
//
// Everything is drawn from the std::mt19937_64 passed in, through core/rng.hpp (no std
// distributions), in a fixed order: the same seed gives bitwise the same room, poses and points
// whatever the thread count (rendering is per-pixel independent; noise is drawn serially).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "datasets/ray_caster.hpp"
#include "protocols/mesh.hpp"

namespace regbench {

/// All simulation parameters (flat, so core/params.hpp's ParseConfig checks every key).
struct IndoorSimOptions {
    // Room (uniform ranges).
    double room_min_side_m = 3.0;       ///< floor width and depth drawn in [min, max]
    double room_max_side_m = 6.0;       ///<
    double room_min_height_m = 2.5;     ///< ceiling height drawn in [min, max]
    double room_max_height_m = 3.0;     ///<
    int min_boxes = 1;                  ///< furniture boxes per room, in [min, max]
    int max_boxes = 4;                  ///<
    double box_min_side_m = 0.3;        ///< box footprint sides in [min, max]
    double box_max_side_m = 1.5;        ///<
    double box_min_height_m = 0.3;      ///< box heights in [min, max]
    double box_max_height_m = 1.2;      ///<
    int min_meshes = 3;                 ///< corpus meshes per room, in [min, max] (0 if no corpus)
    int max_meshes = 6;                 ///<
    double mesh_min_size_m = 0.3;       ///< largest bounding-box side of a placed mesh, [min, max]
    double mesh_max_size_m = 1.5;       ///<
    double on_box_probability = 0.5;    ///< a corpus mesh stands on a free box that fits it (a
                                        ///< table top) with this probability, else on the floor
    double object_wall_margin_m = 0.1;  ///< objects keep this distance from the walls
    int placement_attempts = 30;  ///< tries per object to find a free spot, else it is left out

    // Camera intrinsics (pinhole, pixel centres at integer coordinates). Default: a Kinect
    // (640 x 480, f = 525 px) downscaled by 2 for speed.
    int image_width = 320;   ///< pixels
    int image_height = 240;  ///< pixels
    double fx = 262.5;       ///< focal length [px]
    double fy = 262.5;       ///< focal length [px]
    double cx = 159.5;       ///< principal point [px]
    double cy = 119.5;       ///< principal point [px]

    // Camera placement.
    double camera_min_height_m = 1.0;      ///< eye height in [min, max]
    double camera_max_height_m = 1.8;      ///<
    double camera_wall_clearance_m = 0.4;  ///< cameras stay this far inside the walls and
                                           ///< outside object footprints
    double min_baseline_m = 0.1;           ///< view B = view A moved by a random direction times
    double max_baseline_m = 0.4;           ///< a length in [min, max] ...
    double min_rotation_deg = 5.0;         ///< ... and turned about a random axis by an angle
    double max_rotation_deg = 20.0;        ///< in [min, max]
    int view_attempts = 50;                ///< redraws of a pose pair before giving up (throws)
    int min_valid_points = 4096;           ///< a view with fewer returns is redrawn
    double min_object_fraction = 0.3;  ///< a view whose returns hit furniture (not floor, walls,
                                       ///< ceiling) less often than this, probed on a 16 x 12
                                       ///< ray grid, is redrawn: walls alone are degenerate
    double min_normal_spread = 0.05;   ///< a view whose probed surface normals n have
                                       ///< lambda_min(mean n n^T) below this is redrawn: one
                                       ///< plane (0) or two (0) leave a motion unconstrained

    // Sensor model: missing returns.
    double min_range_m = 0.5;         ///< depths (z) below this return nothing
    double max_range_m = 4.0;         ///< depths (z) beyond this return nothing (Kinect v1)
    double max_incidence_deg = 75.0;  ///< angle between ray and surface normal above this:
                                      ///< no return (grazing)
    // Sensor model: noise (Nguyen et al. 2012).
    bool noise = true;  ///< false: exact depths (no Gaussian noise, no quantisation)
    double axial_sigma_const_m = 0.0012;    ///< sigma_z = c + q (z - z0)^2 + a / sqrt(z) *
    double axial_sigma_quad = 0.0019;       ///<   theta^2 / (pi/2 - theta)^2   (Nguyen eq. 1)
    double axial_sigma_offset_m = 0.4;      ///< z0
    double axial_sigma_angle = 0.0001;      ///< a
    double lateral_sigma_px = 0.8;          ///< sigma_L = p + l theta / (pi/2 - theta) [sensor px]
    double lateral_sigma_angle_px = 0.035;  ///< l (Nguyen eq. 2)
    double sensor_focal_px = 525.0;         ///< focal of the physical sensor, for lateral noise and
                                            ///< disparity (independent of the render resolution)
    double stereo_baseline_m = 0.075;       ///< projector-camera baseline of the disparity model
    int disparity_subpixel = 8;  ///< disparity quantised to 1/this px (Kinect: 8); 0 = off

    // Labels.
    double overlap_eta_m = 0.05;  ///< a point overlaps when the other scan has a point this close
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(
    IndoorSimOptions, room_min_side_m, room_max_side_m, room_min_height_m, room_max_height_m,
    min_boxes, max_boxes, box_min_side_m, box_max_side_m, box_min_height_m, box_max_height_m,
    min_meshes, max_meshes, mesh_min_size_m, mesh_max_size_m, on_box_probability,
    object_wall_margin_m, placement_attempts, image_width, image_height, fx, fy, cx, cy,
    camera_min_height_m, camera_max_height_m, camera_wall_clearance_m, min_baseline_m,
    max_baseline_m, min_rotation_deg, max_rotation_deg, view_attempts, min_valid_points,
    min_object_fraction, min_normal_spread, min_range_m, max_range_m, max_incidence_deg, noise,
    axial_sigma_const_m, axial_sigma_quad, axial_sigma_offset_m, axial_sigma_angle,
    lateral_sigma_px, lateral_sigma_angle_px, sensor_focal_px, stereo_baseline_m,
    disparity_subpixel, overlap_eta_m)

/// Throws std::invalid_argument("indoor: parameter '<name>' ...") on an inconsistent option.
void ValidateIndoorSimOptions(const IndoorSimOptions& options);
/// ParseConfig + ValidateIndoorSimOptions.
IndoorSimOptions ParseIndoorSimOptions(const nlohmann::json& j);

/// Meshes from the corpus, read once and shared by every room (no global cache: the caller owns
/// it and passes it in).
struct FurnitureLibrary {
    std::vector<std::string> names;    ///< file stem, sorted
    std::vector<Mesh> meshes;          ///< as read (any scale; rooms rescale them)
    std::vector<std::string> skipped;  ///< "<file>: <reason>" for files not used
};

/// Reads every *.off in `dir` in sorted file-name order with ReadOff, keeping meshes whose
/// triangle count is in [min_faces, max_faces] and whose bounding box is not flat (every side
/// > 1% of the largest). Others are listed in `skipped`. Throws std::runtime_error naming
/// `dir` when it does not exist or yields no mesh.
FurnitureLibrary LoadFurnitureMeshes(const std::string& dir, int min_faces = 100,
                                     int max_faces = 20000);

/// One object standing in the room.
struct RoomObject {
    std::string name;           ///< "box" or the corpus mesh name
    Eigen::Vector2d centre_xy;  ///< footprint centre [m]
    double radius_m = 0.0;      ///< footprint bounding-circle radius [m]
    double height_m = 0.0;      ///< top above the floor [m]
    double top_radius_m = 0.0;  ///< free circle on its top (an unused box's inscribed circle)
    int support = -1;           ///< index of the object it stands on; -1: the floor
};

/// A furnished room: one triangle mesh (shell first, then objects) and its layout.
struct IndoorRoom {
    Mesh mesh;
    Eigen::Index shell_triangles = 12;  ///< mesh.faces rows before this are floor/walls/ceiling
    Eigen::Vector3d size_m = Eigen::Vector3d::Zero();  ///< width (x), depth (y), height (z)
    std::vector<RoomObject> objects;
};

/// Draws a room: size, boxes, then corpus meshes (random mesh, size, yaw, free spot).
IndoorRoom AssembleRoom(const IndoorSimOptions& options, const FurnitureLibrary& library,
                        std::mt19937_64& rng);

/// Camera pose at `eye` looking at `target`, world z up (no roll): camera z = viewing
/// direction, x = right, y = down. Throws std::invalid_argument if they coincide or the view
/// is vertical.
Transform LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target);

/// Noise-free render: per pixel (row-major, row = v, column = u) the depth z along the optical
/// axis (0 = no hit) and the incidence angle between ray and surface normal [rad].
struct DepthRender {
    int width = 0;
    int height = 0;
    Eigen::VectorXd depth;      ///< z [m], 0 where the ray hit nothing
    Eigen::VectorXd incidence;  ///< [rad] in [0, pi/2]
};
DepthRender RenderDepth(const RayCaster& scene, const IndoorSimOptions& options,
                        const Transform& T_world_camera);

/// Nguyen et al. 2012 eq. 1: axial (depth) noise std [m] at depth z [m], incidence theta [rad].
double KinectAxialSigma(const IndoorSimOptions& options, double z_m, double theta_rad);
/// Nguyen et al. 2012 eq. 2: lateral noise std [m] at depth z [m], incidence theta [rad].
double KinectLateralSigma(const IndoorSimOptions& options, double z_m, double theta_rad);
/// Depth after disparity quantisation d = f b / z rounded to 1/disparity_subpixel px.
double QuantiseDepth(const IndoorSimOptions& options, double z_m);

/// A simulated scan.
struct IndoorScan {
    PointCloud points_camera;  ///< [m], camera frame
    PointCloud points_world;   ///< the same points in the world frame
    Transform T_world_camera = Transform::Identity();
    Eigen::VectorXi pixel;  ///< v * width + u of each point
};

/// Turns a render into points: drops missing returns (no hit, z outside [min_range, max_range],
/// incidence > max_incidence), then with options.noise adds axial noise, quantises disparity
/// and adds lateral noise (pixels in row-major order, 3 normals each), then back-projects.
IndoorScan ScanFromRender(const DepthRender& render, const IndoorSimOptions& options,
                          const Transform& T_world_camera, std::mt19937_64& rng);

/// RenderDepth + ScanFromRender.
IndoorScan SimulateScan(const RayCaster& scene, const IndoorSimOptions& options,
                        const Transform& T_world_camera, std::mt19937_64& rng);

/// Two views of one room.
struct IndoorScanPair {
    IndoorScan a;                             ///< source
    IndoorScan b;                             ///< target
    Transform T_b_a = Transform::Identity();  ///< maps A's camera frame into B's (= T_gt)
    Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> a_overlap;  ///< 1: B has a point within eta
    Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> b_overlap;  ///< of T_b_a * a (and back)
    double a_overlap_ratio = 0.0;
    double b_overlap_ratio = 0.0;
    IndoorRoom room;
    std::string name;  ///< "room(<w>x<d>x<h>):<objects>"
};

/// Per-point overlap labels: 1 where the nearest point of `target` to T_target_source * p is
/// within eta. Returns one label per source point.
Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> OverlapLabels(const PointCloud& source,
                                                             const PointCloud& target,
                                                             const Transform& T_target_source,
                                                             double eta);

/// The generator for the `indoor` protocol's visibility-overlap variant: room, camera A
/// (random free eye position, looking at a random object or wall point), camera B (A moved by
/// the baseline and rotation ranges), both scanned, labels at overlap_eta_m. Views with fewer
/// than min_valid_points returns, or B outside the free space, are redrawn (view_attempts times,
/// then std::runtime_error). Use MakePairRng(seed, pair_index) for pair `pair_index`.
IndoorScanPair SimulateIndoorPair(const IndoorSimOptions& options, const FurnitureLibrary& library,
                                  std::mt19937_64& rng);

/// One view only (the paper resamples both clouds of a Tab. 3 pair from one scan): the same
/// room and camera-A draw as SimulateIndoorPair.
IndoorScan SimulateIndoorScan(const IndoorSimOptions& options, const FurnitureLibrary& library,
                              std::mt19937_64& rng);

}  // namespace regbench
