#include "baselines/icp_pl.hpp"

#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>

#include "baselines/open3d_adapter.hpp"
#include "baselines/schemas.hpp"
#include "core/method_spec.hpp"

namespace regbench {
namespace {

struct IcpPlOptions {  // documented in baselines/icp_pl.schema.json (defaults too)
    double max_correspondence_distance;
    int max_iterations;
    double relative_fitness;
    double relative_rmse;
    double normal_radius;
    int normal_max_nn;
};
// clang-format off
REGBENCH_OPTION_FIELDS(IcpPlOptions, max_correspondence_distance, max_iterations, relative_fitness,
                       relative_rmse, normal_radius, normal_max_nn)
// clang-format on

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

MethodInfo IcpPlMethodInfo() {
    return MakeMethodInfo(SpecOf<IcpPlOptions>(BaselineSchema("icp_pl")), AlignIcpPl);
}

}  // namespace regbench
