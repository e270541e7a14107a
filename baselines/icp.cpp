#include "baselines/icp.hpp"

#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>

#include "baselines/open3d_adapter.hpp"
#include "baselines/schemas.hpp"
#include "core/method_spec.hpp"
#include "core/scale_rule.hpp"

namespace regbench {
namespace {

struct IcpOptions {  // documented in baselines/icp.schema.json (defaults too)
    double max_correspondence_distance;
    int max_iterations;
    double relative_fitness;
    double relative_rmse;
    ScaleRuleMode scale_rule;
};
// clang-format off
REGBENCH_OPTION_FIELDS(IcpOptions, max_correspondence_distance, max_iterations, relative_fitness,
                       relative_rmse, scale_rule)
// clang-format on

AlignResult AlignIcp(const IcpOptions& o,
                     const PointCloud& source,
                     const PointCloud& target,
                     const AlignContext& /*context*/) {
    namespace o3r = open3d::pipelines::registration;
    const o3r::ICPConvergenceCriteria criteria(o.relative_fitness, o.relative_rmse,
                                               o.max_iterations);
    const ScaleRule rule = ResolveScaleRule(source, target);
    const double unit = o.scale_rule == ScaleRuleMode::kAuto ? rule.unit : 1.0;
    const double distance = o.max_correspondence_distance * unit;
    AlignResult result =
        RunOpen3dIcp(ToOpen3d(source), ToOpen3d(target), distance,
                     o3r::TransformationEstimationPointToPoint(/*with_scaling=*/false), criteria);
    result.extra["resolved"] = {{"max_correspondence_distance", distance},
                                {"scale_rule", rule.ToJson()}};
    return result;
}

}  // namespace

MethodInfo IcpMethodInfo() {
    return MakeMethodInfo(SpecOf<IcpOptions>(BaselineSchema("icp")), AlignIcp);
}

}  // namespace regbench
