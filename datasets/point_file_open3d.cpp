// Open3D's readers in their own translation unit (Open3D headers are heavy).
#include <open3d/geometry/PointCloud.h>
#include <open3d/io/PointCloudIO.h>

#include <iostream>
#include <stdexcept>
#include <string>

#include "datasets/point_file.hpp"

namespace regbench {

PointCloud ReadPointFileOpen3D(const std::string& path, Normals* normals,
                               NonFinitePoints non_finite) {
    open3d::geometry::PointCloud cloud;
    open3d::io::ReadPointCloudOption option;
    // Non-finite points (organized PCD scans mark missing depth with NaN) are dropped here,
    // not by Open3D, so the user is told how many: they were dropped without a word.
    option.remove_nan_points = false;
    option.remove_infinite_points = false;
    if (!open3d::io::ReadPointCloud(path, cloud, option)) {
        throw std::runtime_error(path + ": cannot read point cloud (corrupt or truncated file)");
    }
    const std::size_t read = cloud.points_.size();
    cloud.RemoveNonFinitePoints(true, true);
    if (cloud.points_.size() != read && non_finite == NonFinitePoints::kRefuse) {
        throw std::runtime_error(path + ": " + std::to_string(read - cloud.points_.size()) +
                                 " of " + std::to_string(read) +
                                 " points have NaN or Inf coordinates (refused by "
                                 "--nan-points refuse; --nan-points drop drops them)");
    }
    if (cloud.points_.size() != read) {
        std::cerr << "regbench: warning: " << path << ": dropped " << read - cloud.points_.size()
                  << " of " << read << " points with NaN or Inf coordinates\n";
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
