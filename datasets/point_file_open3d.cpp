// Open3D's readers in their own translation unit (Open3D headers are heavy).
#include <open3d/geometry/PointCloud.h>
#include <open3d/io/PointCloudIO.h>

#include <stdexcept>
#include <string>

#include "datasets/point_file.hpp"

namespace regbench {

PointCloud ReadPointFileOpen3D(const std::string& path, Normals* normals) {
    open3d::geometry::PointCloud cloud;
    open3d::io::ReadPointCloudOption option;
    option.remove_nan_points = true;
    option.remove_infinite_points = true;
    if (!open3d::io::ReadPointCloud(path, cloud, option)) {
        throw std::runtime_error(path + ": cannot read point cloud (corrupt or truncated file)");
    }
    if (cloud.points_.empty()) throw std::runtime_error(path + ": point cloud file has no points");
    const auto n = static_cast<Eigen::Index>(cloud.points_.size());
    PointCloud points(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        points.row(i) = cloud.points_[static_cast<std::size_t>(i)].transpose();
    }
    if (normals != nullptr) {
        normals->resize(0, 3);
        if (cloud.HasNormals()) {
            normals->resize(n, 3);
            for (Eigen::Index i = 0; i < n; ++i) {
                normals->row(i) = cloud.normals_[static_cast<std::size_t>(i)].transpose();
            }
        }
    }
    return points;
}

}  // namespace regbench
