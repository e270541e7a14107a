// Indoor scan simulation: room assembly, pinhole depth rendering, Kinect noise, view pairs.
#include "datasets/indoor_sim.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/kd_tree.hpp"
#include "core/math_constants.hpp"
#include "core/params.hpp"
#include "core/rng.hpp"
#include "core/transform.hpp"
#include "datasets/off_reader.hpp"

namespace regbench {
namespace {

constexpr const char* kName = "indoor";
/// Views looking closer to vertical than this (|cos| of the angle to world z) are redrawn:
/// LookAt has no roll-free frame there, and a Kinect held by a person rarely points so.
constexpr double kMaxViewVerticalCos = 0.95;
/// A look-at target closer than this to the eye gives a view filled by one surface.
constexpr double kMinTargetDistanceM = 1.2;
/// Cameras aim between these fractions of an object's height (not at its base or tip).
constexpr double kTargetMinHeightFraction = 0.2;
constexpr double kTargetMaxHeightFraction = 0.8;
/// Cameras stay this far below the ceiling.
constexpr double kCeilingClearanceM = 0.1;
/// A corpus mesh is "flat" (a patch, a plane) when a bounding-box side is below this fraction
/// of its largest side; flat meshes make poor free-standing furniture.
constexpr double kFlatMeshRatio = 0.01;

/// Triangle soup under construction.
class MeshBuilder {
public:
    /// Adds `vertices` (already placed) with `faces` indexing them.
    void Append(const std::vector<Eigen::Vector3d>& vertices,
                const std::vector<Eigen::Vector3i>& faces) {
        const int offset = static_cast<int>(vertices_.size());
        vertices_.insert(vertices_.end(), vertices.begin(), vertices.end());
        for (const auto& f : faces) faces_.emplace_back(f.array() + offset);
    }

    Mesh Build() const {
        Mesh mesh;
        mesh.vertices.resize(static_cast<Eigen::Index>(vertices_.size()), 3);
        mesh.faces.resize(static_cast<Eigen::Index>(faces_.size()), 3);
        for (std::size_t i = 0; i < vertices_.size(); ++i) {
            mesh.vertices.row(static_cast<Eigen::Index>(i)) = vertices_[i].transpose();
        }
        for (std::size_t i = 0; i < faces_.size(); ++i) {
            mesh.faces.row(static_cast<Eigen::Index>(i)) = faces_[i].transpose();
        }
        return mesh;
    }

private:
    std::vector<Eigen::Vector3d> vertices_;
    std::vector<Eigen::Vector3i> faces_;
};

/// Axis-aligned box [lo, hi] turned by `yaw` about the vertical axis through its centre:
/// 8 corners, 12 triangles.
void AppendBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double yaw,
               MeshBuilder& builder) {
    const Eigen::Vector3d centre = 0.5 * (lo + hi);
    const Eigen::Matrix3d R = RotationFromAxisAngle(Eigen::Vector3d::UnitZ(), yaw);
    std::vector<Eigen::Vector3d> corners;
    for (int i = 0; i < 8; ++i) {
        const Eigen::Vector3d c((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                                (i & 4) ? hi.z() : lo.z());
        corners.push_back(centre + R * (c - centre));
    }
    // Two triangles per side: -x, +x, -y, +y, -z, +z.
    const std::vector<Eigen::Vector3i> faces = {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5},
                                                {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},
                                                {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}};
    builder.Append(corners, faces);
}

int UniformCount(std::mt19937_64& rng, int lo, int hi) {
    return lo + static_cast<int>(UniformIndex(rng, static_cast<std::uint64_t>(hi - lo + 1)));
}

/// A free footprint centre for an object of bounding radius `radius`, or false after
/// `placement_attempts` tries (objects do not intersect each other or the walls).
bool PlaceFootprint(const IndoorSimOptions& o, const IndoorRoom& room, double radius,
                    std::mt19937_64& rng, Eigen::Vector2d& centre) {
    const double pad = o.object_wall_margin_m + radius;
    if (2.0 * pad >= room.size_m.x() || 2.0 * pad >= room.size_m.y()) return false;
    for (int attempt = 0; attempt < o.placement_attempts; ++attempt) {
        const double x = UniformReal(rng, pad, room.size_m.x() - pad);
        const double y = UniformReal(rng, pad, room.size_m.y() - pad);
        const Eigen::Vector2d c(x, y);
        bool free = true;
        for (const auto& other : room.objects) {
            if ((c - other.centre_xy).norm() < radius + other.radius_m) free = false;
        }
        if (free) {
            centre = c;
            return true;
        }
    }
    return false;
}

void AddBoxes(const IndoorSimOptions& o, std::mt19937_64& rng, IndoorRoom& room,
              MeshBuilder& builder) {
    const int count = UniformCount(rng, o.min_boxes, o.max_boxes);
    for (int i = 0; i < count; ++i) {
        const double sx = UniformReal(rng, o.box_min_side_m, o.box_max_side_m);
        const double sy = UniformReal(rng, o.box_min_side_m, o.box_max_side_m);
        const double h = UniformReal(rng, o.box_min_height_m, o.box_max_height_m);
        const double yaw = UniformReal(rng, 0.0, kPi);
        const double radius = 0.5 * std::hypot(sx, sy);
        Eigen::Vector2d c;
        if (!PlaceFootprint(o, room, radius, rng, c)) continue;
        AppendBox(Eigen::Vector3d(c.x() - 0.5 * sx, c.y() - 0.5 * sy, 0.0),
                  Eigen::Vector3d(c.x() + 0.5 * sx, c.y() + 0.5 * sy, h), yaw, builder);
        room.objects.push_back({"box", c, radius, h, 0.5 * std::min(sx, sy), -1});
    }
}

/// A random box whose free top fits a footprint of `radius` and leaves room for `height`
/// below the ceiling, or -1 if none does.
int PickSupport(const IndoorRoom& room, double radius, double height, std::mt19937_64& rng) {
    std::vector<int> candidates;
    for (std::size_t i = 0; i < room.objects.size(); ++i) {
        const RoomObject& box = room.objects[i];
        if (box.top_radius_m >= radius && box.height_m + height < room.size_m.z()) {
            candidates.push_back(static_cast<int>(i));
        }
    }
    if (candidates.empty()) return -1;
    return candidates[UniformIndex(rng, candidates.size())];
}

void AddCorpusMeshes(const IndoorSimOptions& o, const FurnitureLibrary& library,
                     std::mt19937_64& rng, IndoorRoom& room, MeshBuilder& builder) {
    if (library.meshes.empty()) return;
    const int count = UniformCount(rng, o.min_meshes, o.max_meshes);
    for (int i = 0; i < count; ++i) {
        const std::size_t pick = UniformIndex(rng, library.meshes.size());
        const double size = UniformReal(rng, o.mesh_min_size_m, o.mesh_max_size_m);
        const double yaw = UniformReal(rng, 0.0, 2.0 * kPi);
        const Mesh& mesh = library.meshes[pick];
        // Scale the largest bounding-box side to `size`, turn by yaw, stand on a box or the floor.
        const Eigen::RowVector3d lo = mesh.vertices.colwise().minCoeff();
        const Eigen::RowVector3d hi = mesh.vertices.colwise().maxCoeff();
        const double scale = size / (hi - lo).maxCoeff();
        const Eigen::Matrix3d R = RotationFromAxisAngle(Eigen::Vector3d::UnitZ(), yaw);
        std::vector<Eigen::Vector3d> placed(static_cast<std::size_t>(mesh.vertices.rows()));
        Eigen::Vector3d placed_lo = Eigen::Vector3d::Constant(INFINITY);
        Eigen::Vector3d placed_hi = -placed_lo;
        for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
            const Eigen::Vector3d p = R * (scale * (mesh.vertices.row(v) - lo).transpose());
            placed[static_cast<std::size_t>(v)] = p;
            placed_lo = placed_lo.cwiseMin(p);
            placed_hi = placed_hi.cwiseMax(p);
        }
        const Eigen::Vector3d anchor(0.5 * (placed_lo.x() + placed_hi.x()),
                                     0.5 * (placed_lo.y() + placed_hi.y()), placed_lo.z());
        double radius = 0.0;
        for (auto& p : placed) {
            p -= anchor;
            radius = std::max(radius, p.head<2>().norm());
        }
        const bool on_box = UniformReal(rng, 0.0, 1.0) < o.on_box_probability;
        const int support =
            on_box ? PickSupport(room, radius, placed_hi.z() - placed_lo.z(), rng) : -1;
        Eigen::Vector3d base = Eigen::Vector3d::Zero();
        if (support >= 0) {
            RoomObject& box = room.objects[static_cast<std::size_t>(support)];
            base << box.centre_xy, box.height_m;
            box.top_radius_m = 0.0;  // one object per table top
        } else {
            Eigen::Vector2d c;
            if (!PlaceFootprint(o, room, radius, rng, c)) continue;
            base.head<2>() = c;
        }
        for (auto& p : placed) p += base;
        std::vector<Eigen::Vector3i> faces(static_cast<std::size_t>(mesh.faces.rows()));
        for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
            faces[static_cast<std::size_t>(f)] = mesh.faces.row(f).transpose();
        }
        builder.Append(placed, faces);
        room.objects.push_back({library.names[pick], base.head<2>(), radius,
                                base.z() + placed_hi.z() - placed_lo.z(), 0.0, support});
    }
}

/// An eye position is free when it is inside the walls (with clearance) and outside every
/// object's footprint (with clearance) unless it is above that object.
bool IsFreeEye(const IndoorSimOptions& o, const IndoorRoom& room, const Eigen::Vector3d& eye) {
    const double clear = o.camera_wall_clearance_m;
    if (eye.x() < clear || eye.x() > room.size_m.x() - clear || eye.y() < clear ||
        eye.y() > room.size_m.y() - clear || eye.z() < clear ||
        eye.z() > room.size_m.z() - kCeilingClearanceM) {
        return false;
    }
    for (const auto& obj : room.objects) {
        const bool beside = (eye.head<2>() - obj.centre_xy).norm() >= obj.radius_m + clear;
        const bool above = eye.z() >= obj.height_m + clear;
        if (!beside && !above) return false;
    }
    return true;
}

Eigen::Vector3d RandomUnitVector(std::mt19937_64& rng) {
    for (;;) {
        const Eigen::Vector3d v(StandardNormal(rng), StandardNormal(rng), StandardNormal(rng));
        const double n = v.norm();
        if (n > 1e-12) return v / n;
    }
}

/// Probe grid for view acceptance: coarse enough to cost ~1% of a render.
constexpr int kProbeColumns = 16;
constexpr int kProbeRows = 12;

/// What a coarse ray grid sees of a view: missing returns excluded.
struct ViewProbe {
    double object_fraction = 0.0;  ///< returns on furniture rather than the room shell
    double normal_spread = 0.0;    ///< smallest eigenvalue of mean(n n^T) over returns
};

/// Probes a view on a kProbeColumns x kProbeRows ray grid. normal_spread is 0 when all surfaces
/// seen share one normal direction (a plane) or two (planes meeting in a line, which leave a
/// sliding direction unconstrained); a well-conditioned view has some of all three
/// (Gelfand et al., "Geometrically stable sampling for the ICP algorithm", 3DIM 2003).
ViewProbe ProbeView(const RayCaster& scene, const IndoorRoom& room, const IndoorSimOptions& o,
                    const Transform& T_world_camera) {
    const Eigen::Matrix3d R = T_world_camera.topLeftCorner<3, 3>();
    const Eigen::Vector3d eye = T_world_camera.topRightCorner<3, 1>();
    const double max_incidence_cos = std::cos(o.max_incidence_deg * kDegToRad);
    int returns = 0;
    int on_objects = 0;
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    for (int row = 0; row < kProbeRows; ++row) {
        for (int col = 0; col < kProbeColumns; ++col) {
            const double u = (col + 0.5) * o.image_width / kProbeColumns - 0.5;
            const double v = (row + 0.5) * o.image_height / kProbeRows - 0.5;
            const Eigen::Vector3d ray =
                R * Eigen::Vector3d((u - o.cx) / o.fx, (v - o.cy) / o.fy, 1.0).normalized();
            const RayHit hit = scene.CastRay(eye, ray);
            if (!hit.hit) continue;
            const double z = (hit.point - eye).dot(R.col(2));
            if (z < o.min_range_m || z > o.max_range_m) continue;
            if (std::abs(hit.normal.dot(ray)) < max_incidence_cos) continue;
            ++returns;
            if (hit.face >= room.shell_triangles) ++on_objects;
            scatter += hit.normal * hit.normal.transpose();
        }
    }
    ViewProbe probe;
    if (returns == 0) return probe;
    probe.object_fraction = room.objects.empty() ? 1.0 : static_cast<double>(on_objects) / returns;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter / returns,
                                                               Eigen::EigenvaluesOnly);
    probe.normal_spread = eigen.eigenvalues().minCoeff();
    return probe;
}

bool AcceptView(const RayCaster& scene, const IndoorRoom& room, const IndoorSimOptions& o,
                const Transform& T_world_camera) {
    const ViewProbe probe = ProbeView(scene, room, o, T_world_camera);
    return probe.object_fraction >= o.min_object_fraction &&
           probe.normal_spread >= o.min_normal_spread;
}

/// Camera A: a free eye looking at a random height of a random object (a random point of the
/// room when there is no furniture), with enough furniture in view. Returns false when
/// `placement_attempts` draws gave no usable view.
bool DrawViewA(const IndoorSimOptions& o, const IndoorRoom& room, const RayCaster& scene,
               std::mt19937_64& rng, Transform& T_world_camera) {
    for (int attempt = 0; attempt < o.placement_attempts; ++attempt) {
        const Eigen::Vector3d eye(UniformReal(rng, 0.0, room.size_m.x()),
                                  UniformReal(rng, 0.0, room.size_m.y()),
                                  UniformReal(rng, o.camera_min_height_m, o.camera_max_height_m));
        Eigen::Vector3d target;
        if (!room.objects.empty()) {
            const auto& obj = room.objects[UniformIndex(rng, room.objects.size())];
            target << obj.centre_xy,
                UniformReal(rng, kTargetMinHeightFraction, kTargetMaxHeightFraction) * obj.height_m;
        } else {
            target << UniformReal(rng, 0.0, room.size_m.x()),
                UniformReal(rng, 0.0, room.size_m.y()), UniformReal(rng, 0.0, room.size_m.z());
        }
        if (!IsFreeEye(o, room, eye)) continue;
        const Eigen::Vector3d view = target - eye;
        if (view.norm() < kMinTargetDistanceM) continue;
        if (std::abs(view.normalized().z()) > kMaxViewVerticalCos) continue;
        const Transform T = LookAt(eye, target);
        if (!AcceptView(scene, room, o, T)) continue;
        T_world_camera = T;
        return true;
    }
    return false;
}

/// Camera B: camera A turned about a random axis (in A's frame) and moved along a random
/// direction. Returns false when `placement_attempts` draws gave no free eye.
bool DrawViewB(const IndoorSimOptions& o, const IndoorRoom& room, const RayCaster& scene,
               const Transform& T_world_a, std::mt19937_64& rng, Transform& T_world_b) {
    for (int attempt = 0; attempt < o.placement_attempts; ++attempt) {
        const Eigen::Vector3d axis = RandomUnitVector(rng);
        const double angle = UniformReal(rng, o.min_rotation_deg, o.max_rotation_deg) * kDegToRad;
        const Eigen::Vector3d direction = RandomUnitVector(rng);
        const double baseline = UniformReal(rng, o.min_baseline_m, o.max_baseline_m);
        const Eigen::Matrix3d R =
            T_world_a.topLeftCorner<3, 3>() * RotationFromAxisAngle(axis, angle);
        const Eigen::Vector3d eye = T_world_a.topRightCorner<3, 1>() + baseline * direction;
        if (!IsFreeEye(o, room, eye)) continue;
        if (std::abs(R.col(2).z()) > kMaxViewVerticalCos) continue;
        const Transform T = MakeTransform(R, eye);
        if (!AcceptView(scene, room, o, T)) continue;
        T_world_b = T;
        return true;
    }
    return false;
}

std::string RoomName(const IndoorRoom& room) {
    char size[64];
    std::snprintf(size, sizeof(size), "room(%.2fx%.2fx%.2f)", room.size_m.x(), room.size_m.y(),
                  room.size_m.z());
    std::string name = size;
    for (std::size_t i = 0; i < room.objects.size(); ++i) {
        name += (i == 0 ? ":" : ",") + room.objects[i].name;
    }
    return name;
}

}  // namespace

void ValidateIndoorSimOptions(const IndoorSimOptions& o) {
    auto range = [](double lo, double hi, const std::string& name_lo, const std::string& name_hi) {
        Require(std::isfinite(lo) && lo >= 0.0, kName, name_lo, "must be finite and >= 0");
        Require(std::isfinite(hi) && hi >= lo, kName, name_hi, "must be finite and >= " + name_lo);
    };
    range(o.room_min_side_m, o.room_max_side_m, "room_min_side_m", "room_max_side_m");
    range(o.room_min_height_m, o.room_max_height_m, "room_min_height_m", "room_max_height_m");
    range(o.box_min_side_m, o.box_max_side_m, "box_min_side_m", "box_max_side_m");
    range(o.box_min_height_m, o.box_max_height_m, "box_min_height_m", "box_max_height_m");
    range(o.mesh_min_size_m, o.mesh_max_size_m, "mesh_min_size_m", "mesh_max_size_m");
    range(o.camera_min_height_m, o.camera_max_height_m, "camera_min_height_m",
          "camera_max_height_m");
    range(o.min_baseline_m, o.max_baseline_m, "min_baseline_m", "max_baseline_m");
    range(o.min_rotation_deg, o.max_rotation_deg, "min_rotation_deg", "max_rotation_deg");
    range(o.min_range_m, o.max_range_m, "min_range_m", "max_range_m");
    Require(o.room_min_side_m > 2.0 * o.camera_wall_clearance_m, kName, "room_min_side_m",
            "must exceed twice camera_wall_clearance_m");
    Require(o.room_min_height_m > o.camera_max_height_m, kName, "room_min_height_m",
            "must exceed camera_max_height_m");
    Require(o.mesh_min_size_m > 0.0, kName, "mesh_min_size_m", "must be > 0");
    Require(o.min_boxes >= 0 && o.max_boxes >= o.min_boxes, kName, "max_boxes",
            "must be >= min_boxes >= 0");
    Require(o.min_meshes >= 0 && o.max_meshes >= o.min_meshes, kName, "max_meshes",
            "must be >= min_meshes >= 0");
    Require(o.on_box_probability >= 0.0 && o.on_box_probability <= 1.0, kName, "on_box_probability",
            "must be in [0, 1]");
    Require(o.object_wall_margin_m >= 0.0, kName, "object_wall_margin_m", "must be >= 0");
    Require(o.camera_wall_clearance_m >= 0.0, kName, "camera_wall_clearance_m", "must be >= 0");
    Require(o.placement_attempts >= 1, kName, "placement_attempts", "must be >= 1");
    Require(o.view_attempts >= 1, kName, "view_attempts", "must be >= 1");
    Require(o.image_width >= 1 && o.image_height >= 1, kName, "image_width",
            "and image_height must be >= 1");
    Require(o.fx > 0.0 && o.fy > 0.0, kName, "fx", "and fy must be > 0");
    Require(std::isfinite(o.cx) && std::isfinite(o.cy), kName, "cx", "and cy must be finite");
    Require(o.min_valid_points >= 1, kName, "min_valid_points", "must be >= 1");
    Require(o.max_incidence_deg > 0.0 && o.max_incidence_deg <= 90.0, kName, "max_incidence_deg",
            "must be in (0, 90]");
    Require(o.axial_sigma_const_m >= 0.0 && o.axial_sigma_quad >= 0.0 && o.axial_sigma_angle >= 0.0,
            kName, "axial_sigma_*", "must be >= 0");
    Require(o.lateral_sigma_px >= 0.0 && o.lateral_sigma_angle_px >= 0.0, kName, "lateral_sigma_*",
            "must be >= 0");
    Require(o.sensor_focal_px > 0.0, kName, "sensor_focal_px", "must be > 0");
    Require(o.stereo_baseline_m > 0.0, kName, "stereo_baseline_m", "must be > 0");
    Require(o.disparity_subpixel >= 0, kName, "disparity_subpixel", "must be >= 0 (0 = off)");
    Require(o.min_object_fraction >= 0.0 && o.min_object_fraction <= 1.0, kName,
            "min_object_fraction", "must be in [0, 1]");
    Require(o.min_normal_spread >= 0.0 && o.min_normal_spread <= 1.0 / 3.0, kName,
            "min_normal_spread", "must be in [0, 1/3]");
    Require(o.overlap_eta_m > 0.0, kName, "overlap_eta_m", "must be > 0");
}

IndoorSimOptions ParseIndoorSimOptions(const nlohmann::json& j) {
    IndoorSimOptions options = ParseConfig<IndoorSimOptions>(j, kName);
    ValidateIndoorSimOptions(options);
    return options;
}

FurnitureLibrary LoadFurnitureMeshes(const std::string& dir, int min_faces, int max_faces) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) {
        throw std::runtime_error(dir + ": furniture mesh directory not found");
    }
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(dir)) {
        if (entry.is_regular_file() && entry.path().extension() == ".off") {
            files.push_back(entry.path());
        }
    }
    std::sort(files.begin(), files.end());
    FurnitureLibrary library;
    for (const auto& file : files) {
        const std::string label = file.filename().string();
        Mesh mesh;
        try {
            mesh = ReadOff(file.string());
        } catch (const std::exception& e) {
            library.skipped.push_back(label + ": " + e.what());
            continue;
        }
        const Eigen::Index faces = mesh.faces.rows();
        if (faces < min_faces || faces > max_faces) {
            library.skipped.push_back(label + ": " + std::to_string(faces) +
                                      " triangles, outside [" + std::to_string(min_faces) + ", " +
                                      std::to_string(max_faces) + "]");
            continue;
        }
        const Eigen::RowVector3d extent =
            mesh.vertices.colwise().maxCoeff() - mesh.vertices.colwise().minCoeff();
        if (!(extent.minCoeff() > kFlatMeshRatio * extent.maxCoeff())) {
            library.skipped.push_back(label + ": flat bounding box");
            continue;
        }
        library.names.push_back(file.stem().string());
        library.meshes.push_back(std::move(mesh));
    }
    if (library.meshes.empty()) {
        throw std::runtime_error(dir + ": no usable .off mesh (" +
                                 std::to_string(library.skipped.size()) + " skipped)");
    }
    return library;
}

IndoorRoom AssembleRoom(const IndoorSimOptions& options, const FurnitureLibrary& library,
                        std::mt19937_64& rng) {
    IndoorRoom room;
    room.size_m << UniformReal(rng, options.room_min_side_m, options.room_max_side_m),
        UniformReal(rng, options.room_min_side_m, options.room_max_side_m),
        UniformReal(rng, options.room_min_height_m, options.room_max_height_m);
    MeshBuilder builder;
    AppendBox(Eigen::Vector3d::Zero(), room.size_m, 0.0, builder);  // floor, ceiling, walls
    room.shell_triangles = 12;
    AddBoxes(options, rng, room, builder);
    AddCorpusMeshes(options, library, rng, room, builder);
    room.mesh = builder.Build();
    return room;
}

Transform LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
    const Eigen::Vector3d forward = target - eye;
    if (!(forward.norm() > 0.0)) throw std::invalid_argument("LookAt: eye equals target");
    const Eigen::Vector3d z = forward.normalized();
    const Eigen::Vector3d x_raw = z.cross(Eigen::Vector3d::UnitZ());
    if (!(x_raw.norm() > 1e-9)) throw std::invalid_argument("LookAt: vertical view direction");
    const Eigen::Vector3d x = x_raw.normalized();  // right
    const Eigen::Vector3d y = z.cross(x);          // down
    Eigen::Matrix3d R;
    R.col(0) = x;
    R.col(1) = y;
    R.col(2) = z;
    return MakeTransform(R, eye);
}

DepthRender RenderDepth(const RayCaster& scene, const IndoorSimOptions& o,
                        const Transform& T_world_camera) {
    DepthRender render;
    render.width = o.image_width;
    render.height = o.image_height;
    const Eigen::Index n = static_cast<Eigen::Index>(o.image_width) * o.image_height;
    render.depth = Eigen::VectorXd::Zero(n);
    render.incidence = Eigen::VectorXd::Zero(n);
    const Eigen::Matrix3d R = T_world_camera.topLeftCorner<3, 3>();
    const Eigen::Vector3d eye = T_world_camera.topRightCorner<3, 1>();
    // Pixels are independent, so the thread count cannot change the result.
#pragma omp parallel for schedule(dynamic, 8)
    for (int v = 0; v < o.image_height; ++v) {
        for (int u = 0; u < o.image_width; ++u) {
            const Eigen::Vector3d ray_camera((u - o.cx) / o.fx, (v - o.cy) / o.fy, 1.0);
            const Eigen::Vector3d ray_world = R * ray_camera.normalized();
            const RayHit hit = scene.CastRay(eye, ray_world);
            if (!hit.hit) continue;
            const Eigen::Index i = static_cast<Eigen::Index>(v) * o.image_width + u;
            render.depth[i] = (hit.point - eye).dot(R.col(2));  // z along the optical axis
            const double cos_incidence = std::min(1.0, std::abs(hit.normal.dot(ray_world)));
            render.incidence[i] = std::acos(cos_incidence);
        }
    }
    return render;
}

double KinectAxialSigma(const IndoorSimOptions& o, double z_m, double theta_rad) {
    const double dz = z_m - o.axial_sigma_offset_m;
    const double grazing = theta_rad / (0.5 * kPi - theta_rad);
    return o.axial_sigma_const_m + o.axial_sigma_quad * dz * dz +
           o.axial_sigma_angle / std::sqrt(z_m) * grazing * grazing;
}

double KinectLateralSigma(const IndoorSimOptions& o, double z_m, double theta_rad) {
    const double sigma_px =
        o.lateral_sigma_px + o.lateral_sigma_angle_px * theta_rad / (0.5 * kPi - theta_rad);
    return sigma_px * z_m / o.sensor_focal_px;  // pixels of the physical sensor -> metres
}

double QuantiseDepth(const IndoorSimOptions& o, double z_m) {
    if (o.disparity_subpixel == 0 || !(z_m > 0.0)) return z_m;
    const double fb = o.sensor_focal_px * o.stereo_baseline_m;
    const double steps = std::round(fb / z_m * o.disparity_subpixel);
    if (steps < 1.0) return z_m;  // beyond the quantiser's last level: leave as is
    return fb / (steps / o.disparity_subpixel);
}

IndoorScan ScanFromRender(const DepthRender& render, const IndoorSimOptions& o,
                          const Transform& T_world_camera, std::mt19937_64& rng) {
    const double max_incidence = o.max_incidence_deg * kDegToRad;
    std::vector<Eigen::Vector3d> points;
    std::vector<int> pixels;
    points.reserve(static_cast<std::size_t>(render.depth.size()));
    for (int v = 0; v < render.height; ++v) {
        for (int u = 0; u < render.width; ++u) {
            const int i = v * render.width + u;
            const double z = render.depth[i];
            const double theta = render.incidence[i];
            // Missing returns: nothing hit, out of range, grazing incidence.
            if (!(z > 0.0) || z < o.min_range_m || z > o.max_range_m || theta > max_incidence) {
                continue;
            }
            double z_measured = z;
            Eigen::Vector2d lateral = Eigen::Vector2d::Zero();
            if (o.noise) {
                z_measured = z + KinectAxialSigma(o, z, theta) * StandardNormal(rng);
                z_measured = QuantiseDepth(o, z_measured);
                const double sigma_l = KinectLateralSigma(o, z, theta);
                lateral.x() = sigma_l * StandardNormal(rng);
                lateral.y() = sigma_l * StandardNormal(rng);
            }
            if (!(z_measured > 0.0)) continue;
            points.emplace_back((u - o.cx) / o.fx * z_measured + lateral.x(),
                                (v - o.cy) / o.fy * z_measured + lateral.y(), z_measured);
            pixels.push_back(i);
        }
    }
    IndoorScan scan;
    scan.T_world_camera = T_world_camera;
    scan.points_camera.resize(static_cast<Eigen::Index>(points.size()), 3);
    scan.pixel.resize(static_cast<Eigen::Index>(pixels.size()));
    for (std::size_t k = 0; k < points.size(); ++k) {
        scan.points_camera.row(static_cast<Eigen::Index>(k)) = points[k].transpose();
        scan.pixel[static_cast<Eigen::Index>(k)] = pixels[k];
    }
    scan.points_world = Apply(T_world_camera, scan.points_camera);
    return scan;
}

IndoorScan SimulateScan(const RayCaster& scene, const IndoorSimOptions& options,
                        const Transform& T_world_camera, std::mt19937_64& rng) {
    return ScanFromRender(RenderDepth(scene, options, T_world_camera), options, T_world_camera,
                          rng);
}

Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> OverlapLabels(const PointCloud& source,
                                                             const PointCloud& target,
                                                             const Transform& T_target_source,
                                                             double eta) {
    Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> labels =
        Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1>::Zero(source.rows());
    if (target.rows() == 0) return labels;
    const KdTree tree(target);
    const PointCloud moved = Apply(T_target_source, source);
    const Eigen::VectorXd distances = NearestDistances(tree, moved);
    for (Eigen::Index i = 0; i < source.rows(); ++i) labels[i] = distances[i] <= eta ? 1 : 0;
    return labels;
}

IndoorScanPair SimulateIndoorPair(const IndoorSimOptions& options, const FurnitureLibrary& library,
                                  std::mt19937_64& rng) {
    ValidateIndoorSimOptions(options);
    IndoorScanPair pair;
    pair.room = AssembleRoom(options, library, rng);
    const RayCaster scene(pair.room.mesh);
    for (int attempt = 0; attempt < options.view_attempts; ++attempt) {
        Transform T_world_a;
        Transform T_world_b;
        if (!DrawViewA(options, pair.room, scene, rng, T_world_a)) continue;
        if (!DrawViewB(options, pair.room, scene, T_world_a, rng, T_world_b)) continue;
        pair.a = SimulateScan(scene, options, T_world_a, rng);
        pair.b = SimulateScan(scene, options, T_world_b, rng);
        if (pair.a.points_camera.rows() < options.min_valid_points ||
            pair.b.points_camera.rows() < options.min_valid_points) {
            continue;
        }
        pair.T_b_a = Compose(InvertRigid(T_world_b), T_world_a);
        pair.a_overlap = OverlapLabels(pair.a.points_camera, pair.b.points_camera, pair.T_b_a,
                                       options.overlap_eta_m);
        pair.b_overlap = OverlapLabels(pair.b.points_camera, pair.a.points_camera,
                                       InvertRigid(pair.T_b_a), options.overlap_eta_m);
        pair.a_overlap_ratio = pair.a_overlap.cast<double>().mean();
        pair.b_overlap_ratio = pair.b_overlap.cast<double>().mean();
        pair.name = RoomName(pair.room);
        return pair;
    }
    throw std::runtime_error("indoor: no usable pair of views after " +
                             std::to_string(options.view_attempts) + " attempts in " +
                             RoomName(pair.room));
}

IndoorScan SimulateIndoorScan(const IndoorSimOptions& options, const FurnitureLibrary& library,
                              std::mt19937_64& rng) {
    ValidateIndoorSimOptions(options);
    const IndoorRoom room = AssembleRoom(options, library, rng);
    const RayCaster scene(room.mesh);
    for (int attempt = 0; attempt < options.view_attempts; ++attempt) {
        Transform T_world_camera;
        if (!DrawViewA(options, room, scene, rng, T_world_camera)) continue;
        IndoorScan scan = SimulateScan(scene, options, T_world_camera, rng);
        if (scan.points_camera.rows() >= options.min_valid_points) return scan;
    }
    throw std::runtime_error("indoor: no usable view after " +
                             std::to_string(options.view_attempts) + " attempts in " +
                             RoomName(room));
}

}  // namespace regbench
