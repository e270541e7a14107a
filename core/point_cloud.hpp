#pragma once
// Point cloud type shared by every regbench component.
#include <Eigen/Core>

namespace regbench {

/// N x 3 points, row-major so each point's x, y, z are contiguous (nanoflann, HDF5 and
/// Open3D's std::vector<Eigen::Vector3d> all read this layout without a transpose).
using PointCloud = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// Per-point unit normals, same layout as PointCloud.
using Normals = PointCloud;
/// Homogeneous rigid (or similarity) transform; names say which frames it maps.
using Transform = Eigen::Matrix4d;

}  // namespace regbench
