#pragma once
// Shared glue for the PCL-backed methods (gicp, ndt). Include only from PCL translation units.
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "core/point_cloud.hpp"

namespace regbench {

/// Copies a regbench cloud into a PCL cloud. PCL's registration runs in float32.
pcl::PointCloud<pcl::PointXYZ>::Ptr ToPcl(const PointCloud& points);

/// Converts PCL's float32 result to double and projects its rotation block onto SO(3)
/// (SVD, det +1), since float rounding leaves R orthonormal only to ~1e-7 per entry.
Transform FromPclTransform(const Eigen::Matrix4f& T);

}  // namespace regbench
