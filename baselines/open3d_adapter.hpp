#pragma once
// Shared glue for the Open3D-backed methods (icp, icp-pl, fgr). Include only from Open3D
// translation units: this header pulls Open3D's headers in.
#include <open3d/geometry/PointCloud.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>

#include "core/point_cloud.hpp"
#include "core/registration.hpp"

namespace regbench {

/// Copies a regbench cloud into an Open3D cloud (double precision, no normals).
open3d::geometry::PointCloud ToOpen3d(const PointCloud& points);

/// Runs open3d::pipelines::registration::RegistrationICP from the identity and fills an
/// AlignResult: the transform, the iteration count (Open3D does not report it, so the
/// estimation is wrapped and its ComputeTransformation calls are counted), the stop reason
/// and extra = {fitness, inlier_rmse, correspondences}.
AlignResult RunOpen3dIcp(
    const open3d::geometry::PointCloud& source,
    const open3d::geometry::PointCloud& target,
    double max_correspondence_distance,
    const open3d::pipelines::registration::TransformationEstimation& estimation,
    const open3d::pipelines::registration::ICPConvergenceCriteria& criteria);

}  // namespace regbench
