#pragma once
// Shared glue for the Open3D-backed methods (icp, icp-pl, fgr). Include only from Open3D
// translation units: this header pulls Open3D's headers in.
#include <open3d/geometry/PointCloud.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>

#include "core/params.hpp"
#include "core/point_cloud.hpp"
#include "core/registration.hpp"

namespace regbench {

/// Copies a regbench cloud into an Open3D cloud (double precision, no normals).
open3d::geometry::PointCloud ToOpen3d(const PointCloud& points);

/// The options icp and icp-pl share: the correspondence radius and Open3D's
/// ICPConvergenceCriteria. Both methods' options derive from it and bind these fields with
/// their own docs.
struct Open3dIcpOptions {
    /// pairs farther apart are ignored [unit-sphere units]
    double max_correspondence_distance = 1.0;
    int max_iterations = 30;         ///< iteration cap
    double relative_fitness = 1e-6;  ///< stop threshold on the fitness change
    double relative_rmse = 1e-6;     ///< stop threshold on the inlier-RMSE change

    /// The ranges of these fields (core/params.hpp; `regbench methods` prints them).
    void Validate(ParamCheck& c) const {
        c.Above("max_correspondence_distance", max_correspondence_distance, 0.0);
        c.AtLeast("max_iterations", max_iterations, 1);
        c.AtLeast("relative_fitness", relative_fitness, 0.0);
        c.AtLeast("relative_rmse", relative_rmse, 0.0);
    }
    /// Scale guard class: kd-tree searches, O((N + M) log M).
    CostClass Cost() const { return CostClass::kNearLinear; }
    open3d::pipelines::registration::ICPConvergenceCriteria Criteria() const {
        return {relative_fitness, relative_rmse, max_iterations};
    }
};

/// Runs open3d::pipelines::registration::RegistrationICP from the identity and fills an
/// AlignResult: the transform, the iteration count (Open3D does not report it, so the
/// estimation is wrapped and its ComputeTransformation calls are counted), the stop reason
/// and extra = {fitness, inlier_rmse, correspondences}.
AlignResult RunOpen3dIcp(
    const open3d::geometry::PointCloud& source, const open3d::geometry::PointCloud& target,
    double max_correspondence_distance,
    const open3d::pipelines::registration::TransformationEstimation& estimation,
    const open3d::pipelines::registration::ICPConvergenceCriteria& criteria);

}  // namespace regbench
