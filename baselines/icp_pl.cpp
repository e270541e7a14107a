#include "baselines/icp_pl.hpp"

#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>

#include "baselines/open3d_adapter.hpp"
#include "core/params.hpp"
#include "core/scale_rule.hpp"

namespace regbench {
namespace {

/// max_correspondence_distance, max_iterations, relative_fitness and relative_rmse are the
/// Open3dIcpOptions base (baselines/open3d_adapter.hpp).
struct IcpPlOptions : Open3dIcpOptions {
    double normal_radius = 0.1;  ///< target-normal neighbourhood radius
    int normal_max_nn = 30;      ///< neighbour cap per normal
    ScaleRuleMode scale_rule = ScaleRuleMode::kAuto;  ///< "auto" or "preset"
    double scale_rule_radius = kScaleRuleReferenceRadius;  ///< [unit-sphere units]

    template <class F>
    void Fields(F&& f) {
        f("max_correspondence_distance", max_correspondence_distance,
          "pairs farther apart are ignored [unit-sphere units]; 1.0 as `icp`, so the two "
          "ICPs differ only in the cost");
        f("max_iterations", max_iterations, "iteration cap; 30 = Open3D default, as `icp`");
        f("relative_fitness", relative_fitness,
          "stop threshold on the fitness change; 1e-6 = Open3D default");
        f("relative_rmse", relative_rmse,
          "stop threshold on the inlier-RMSE change [unit-sphere units]: Open3D compares the "
          "absolute change; 1e-6 = Open3D default");
        f("normal_radius", normal_radius,
          "target-normal neighbourhood radius [unit-sphere units]; 0.1 = 2 * voxel (0.05), "
          "Open3D tutorial "
          "recipe, ~2x the sample spacing of a unit-sphere object");
        f("normal_max_nn", normal_max_nn, "neighbour cap per normal; 30 = Open3D tutorial recipe");
        f("scale_rule", scale_rule,
          "\"auto\": as `icp`, max_correspondence_distance and normal_radius scaled by the "
          "pair's unit (RMS radius / 0.6 when outside [0.5, 2], else 1; docs/performance.md), "
          "the values used in extra.resolved; \"preset\": as given");
        f("scale_rule_radius", scale_rule_radius, kScaleRuleRadiusDoc);
    }
    void Validate(ParamCheck& c) const {
        Open3dIcpOptions::Validate(c);
        c.Above("scale_rule_radius", scale_rule_radius, 0.0);
        c.Above("normal_radius", normal_radius, 0.0);
        c.AtLeast("normal_max_nn", normal_max_nn, 3);
    }
};

AlignResult AlignIcpPl(const IcpPlOptions& o, const PointCloud& source, const PointCloud& target,
                       const AlignContext& /*context*/) {
    namespace o3r = open3d::pipelines::registration;
    // Point-to-plane (Chen & Medioni 1992) minimises distances along the target's normals,
    // so only the target needs them.
    const ScaleRule rule = ResolveScaleRule(source, target, o.scale_rule_radius);
    const double unit = o.scale_rule == ScaleRuleMode::kAuto ? rule.unit : 1.0;
    const double distance = o.max_correspondence_distance * unit;
    open3d::geometry::PointCloud target_o3d = ToOpen3d(target);
    target_o3d.EstimateNormals(
        open3d::geometry::KDTreeSearchParamHybrid(o.normal_radius * unit, o.normal_max_nn));
    AlignResult result = RunOpen3dIcp(ToOpen3d(source), target_o3d, distance,
                                      o3r::TransformationEstimationPointToPlane(), o.Criteria());
    result.extra["resolved"] = {{"max_correspondence_distance", distance},
                                {"normal_radius", o.normal_radius * unit},
                                {"scale_rule", rule.ToJson()}};
    return result;
}

}  // namespace

MethodInfo IcpPlMethodInfo() {
    return MakeMethodInfo<IcpPlOptions>(
        "icp-pl",
        "point-to-plane ICP from the identity (Open3D RegistrationICP), target normals by Open3D "
        "EstimateNormals (hybrid radius/kNN)",
        AlignIcpPl);
}

}  // namespace regbench
