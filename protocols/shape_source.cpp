#include "protocols/shape_source.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <utility>

#include "core/rng.hpp"

namespace regbench {

ShapeSource ShapeSource::FromMesh(Mesh mesh, std::string name, std::string category) {
    const Eigen::Index nv = mesh.vertices.rows();
    if (mesh.faces.rows() > 0 && (mesh.faces.minCoeff() < 0 || mesh.faces.maxCoeff() >= nv)) {
        throw std::invalid_argument("shape '" + name + "': face index out of range");
    }
    if (!mesh.vertices.allFinite()) {
        throw std::invalid_argument("shape '" + name + "': non-finite vertex");
    }
    auto cumulative = std::make_shared<std::vector<double>>();
    cumulative->reserve(static_cast<std::size_t>(mesh.faces.rows()));
    double total = 0.0;
    for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
        const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0)).transpose();
        const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1)).transpose();
        const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2)).transpose();
        total += 0.5 * (b - a).cross(c - a).norm();
        cumulative->push_back(total);
    }
    if (!(total > 0.0)) {
        throw std::invalid_argument("shape '" + name + "': mesh has no face of positive area");
    }
    ShapeSource s;
    s.name_ = std::move(name);
    s.category_ = std::move(category);
    s.mesh_ = std::make_shared<const Mesh>(std::move(mesh));
    s.cumulative_area_ = std::move(cumulative);
    return s;
}

ShapeSource ShapeSource::FromPoints(PointCloud points, std::string name, std::string category) {
    if (points.rows() == 0) throw std::invalid_argument("shape '" + name + "': no points");
    if (!points.allFinite()) throw std::invalid_argument("shape '" + name + "': non-finite point");
    ShapeSource s;
    s.name_ = std::move(name);
    s.category_ = std::move(category);
    s.points_ = std::make_shared<const PointCloud>(std::move(points));
    return s;
}

namespace {

/// Rigid within `tol` (float32 files), then with R replaced by its nearest rotation (SVD), so
/// the pair file's stricter rigidity check holds.
Transform CheckedRigid(const Transform& T, const std::string& name) {
    constexpr double kStoredRigidTolerance = 1e-4;
    const auto fail = [&](const std::string& why) {
        throw std::invalid_argument("shape '" + name + "': stored transform " + why);
    };
    if (!T.allFinite()) fail("has a non-finite entry");
    if ((T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > kStoredRigidTolerance) {
        fail("has a last row other than 0 0 0 1");
    }
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() >
        kStoredRigidTolerance) {
        fail("is not rigid (R^T R differs from I by more than 1e-4)");
    }
    if (R.determinant() < 0) fail("is a reflection (det R < 0)");
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Transform out = Transform::Identity();
    out.topLeftCorner<3, 3>() = svd.matrixU() * svd.matrixV().transpose();
    out.topRightCorner<3, 1>() = T.topRightCorner<3, 1>();
    return out;
}

}  // namespace

ShapeSource ShapeSource::FromStoredPair(PointCloud source, PointCloud target,
                                        const Transform& target_from_source, std::string name,
                                        std::string category) {
    if (target.rows() == 0) throw std::invalid_argument("shape '" + name + "': empty target");
    if (!target.allFinite()) {
        throw std::invalid_argument("shape '" + name + "': non-finite target point");
    }
    const Transform T = CheckedRigid(target_from_source, name);
    ShapeSource s = FromPoints(std::move(source), std::move(name), std::move(category));
    s.stored_target_ = std::make_shared<const PointCloud>(std::move(target));
    s.stored_transform_ = T;
    return s;
}

const PointCloud& ShapeSource::stored_source() const {
    if (!has_stored_pair()) throw std::logic_error("shape '" + name_ + "' stores no pair");
    return *points_;
}

const PointCloud& ShapeSource::stored_target() const {
    if (!has_stored_pair()) throw std::logic_error("shape '" + name_ + "' stores no pair");
    return *stored_target_;
}

const Transform& ShapeSource::stored_transform() const {
    if (!has_stored_pair()) throw std::logic_error("shape '" + name_ + "' stores no pair");
    return stored_transform_;
}

Eigen::Index ShapeSource::size() const { return is_mesh() ? mesh_->faces.rows() : points_->rows(); }

PointCloud ShapeSource::Sample(Eigen::Index n, std::mt19937_64& rng) const {
    if (n < 0) throw std::invalid_argument("shape '" + name_ + "': negative sample size");
    return is_mesh() ? SampleMesh(n, rng) : SamplePoints(n, rng);
}

PointCloud ShapeSource::SampleMesh(Eigen::Index n, std::mt19937_64& rng) const {
    const std::vector<double>& cum = *cumulative_area_;
    const double total = cum.back();
    PointCloud out(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        // Area-weighted face choice: first face whose running area exceeds u.
        const double u = UniformReal(rng, 0.0, total);
        const auto it = std::upper_bound(cum.begin(), cum.end(), u);
        const Eigen::Index f = std::min<Eigen::Index>(static_cast<Eigen::Index>(it - cum.begin()),
                                                      mesh_->faces.rows() - 1);
        const double r1 = std::sqrt(UniformReal(rng, 0.0, 1.0));
        const double r2 = UniformReal(rng, 0.0, 1.0);
        // p = (1 - sqrt(r1)) a + sqrt(r1) (1 - r2) b + sqrt(r1) r2 c  (uniform on the triangle).
        out.row(i) = (1.0 - r1) * mesh_->vertices.row(mesh_->faces(f, 0)) +
                     r1 * (1.0 - r2) * mesh_->vertices.row(mesh_->faces(f, 1)) +
                     r1 * r2 * mesh_->vertices.row(mesh_->faces(f, 2));
    }
    return out;
}

PointCloud ShapeSource::SamplePoints(Eigen::Index n, std::mt19937_64& rng) const {
    const PointCloud& pts = *points_;
    if (n > pts.rows()) {
        throw std::invalid_argument(
            "shape '" + name_ + "' has " + std::to_string(pts.rows()) + " points, fewer than the " +
            std::to_string(n) + " sampled per cloud: pass --points " + std::to_string(pts.rows()) +
            " (or less), or leave this cloud out");
    }
    std::vector<Eigen::Index> index(static_cast<std::size_t>(pts.rows()));
    std::iota(index.begin(), index.end(), Eigen::Index{0});
    PointCloud out(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        // Partial Fisher-Yates: position i receives a uniform pick among the untaken points.
        const auto remaining = static_cast<std::uint64_t>(pts.rows() - i);
        const auto j = static_cast<std::size_t>(i) + UniformIndex(rng, remaining);
        std::swap(index[static_cast<std::size_t>(i)], index[j]);
        out.row(i) = pts.row(index[static_cast<std::size_t>(i)]);
    }
    return out;
}

}  // namespace regbench
