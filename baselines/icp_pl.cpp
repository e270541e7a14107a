#include "baselines/icp_pl.hpp"

#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>

#include "baselines/open3d_adapter.hpp"
#include "core/method_spec.hpp"

namespace regbench {
namespace {

constexpr const char* kName = "icp-pl";

struct IcpPlOptions {  // each member documented once, in Spec()
    double max_correspondence_distance = 1.0;
    int max_iterations = 30;
    double relative_fitness = 1e-6;
    double relative_rmse = 1e-6;
    double normal_radius = 0.1;
    int normal_max_nn = 30;
};

const MethodSpec<IcpPlOptions>& Spec() {
    static const MethodSpec<IcpPlOptions> spec{
        kName,
        "point-to-plane ICP from the identity (Open3D RegistrationICP), target normals by "
        "Open3D EstimateNormals (hybrid radius/kNN)",
        {
            Param("max_correspondence_distance", &IcpPlOptions::max_correspondence_distance,
                  "pairs farther apart are ignored [unit-sphere units], > 0; 1.0 as `icp`, so the "
                  "two ICPs differ only in the cost")
                .Greater(0.0),
            Param("max_iterations", &IcpPlOptions::max_iterations,
                  "iteration cap, >= 1; 30 = Open3D default, as `icp`")
                .AtLeast(1),
            Param("relative_fitness", &IcpPlOptions::relative_fitness,
                  "stop threshold on the fitness change, >= 0; 1e-6 = Open3D default")
                .AtLeast(0.0),
            Param("relative_rmse", &IcpPlOptions::relative_rmse,
                  "stop threshold on the inlier-RMSE change, >= 0; 1e-6 = Open3D default")
                .AtLeast(0.0),
            Param("normal_radius", &IcpPlOptions::normal_radius,
                  "target-normal neighbourhood radius, > 0; 0.1 = 2 * voxel (0.05), Open3D "
                  "tutorial recipe, ~2x the sample spacing of a unit-sphere object")
                .Greater(0.0),
            Param("normal_max_nn", &IcpPlOptions::normal_max_nn,
                  "neighbour cap per normal, >= 3; 30 = Open3D tutorial recipe")
                .AtLeast(3),
        },
        nullptr,
        {}};
    return spec;
}

AlignResult AlignIcpPl(const IcpPlOptions& o,
                       const PointCloud& source,
                       const PointCloud& target,
                       const AlignContext& /*context*/) {
    namespace o3r = open3d::pipelines::registration;
    // Point-to-plane (Chen & Medioni 1992) minimises distances along the target's normals,
    // so only the target needs them.
    open3d::geometry::PointCloud target_o3d = ToOpen3d(target);
    target_o3d.EstimateNormals(
        open3d::geometry::KDTreeSearchParamHybrid(o.normal_radius, o.normal_max_nn));
    const o3r::ICPConvergenceCriteria criteria(o.relative_fitness, o.relative_rmse,
                                               o.max_iterations);
    return RunOpen3dIcp(ToOpen3d(source), target_o3d, o.max_correspondence_distance,
                        o3r::TransformationEstimationPointToPlane(), criteria);
}

}  // namespace

MethodInfo IcpPlMethodInfo() { return MakeMethodInfo(Spec(), AlignIcpPl); }

}  // namespace regbench
