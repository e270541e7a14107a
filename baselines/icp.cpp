#include "baselines/icp.hpp"

#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>

#include "baselines/open3d_adapter.hpp"
#include "core/params.hpp"
#include "core/scale_rule.hpp"

namespace regbench {
namespace {

/// max_correspondence_distance, max_iterations, relative_fitness and relative_rmse are the
/// Open3dIcpOptions base (baselines/open3d_adapter.hpp).
struct IcpOptions : Open3dIcpOptions {
    ScaleRuleMode scale_rule = ScaleRuleMode::kAuto;  ///< "auto" or "preset"
    double scale_rule_radius = kScaleRuleReferenceRadius;  ///< [unit-sphere units]

    template <class F>
    void Fields(F&& f) {
        f("max_correspondence_distance", max_correspondence_distance,
          "pairs farther apart are ignored [unit-sphere units]; 1.0 covers the protocols' "
          "motions (translation up to 0.5 per axis) from the identity; 0.07 = 2 * overlap_radius "
          "is the OGMM code's radius for refining a network's estimate, where ICP barely moves");
        f("max_iterations", max_iterations, "iteration cap; 30 = Open3D default, as the OGMM code");
        f("scale_rule", scale_rule,
          "\"auto\": max_correspondence_distance is scaled by the pair's unit (RMS radius / 0.6 "
          "when outside [0.5, 2], else 1: unit-sphere objects keep the preset; "
          "docs/performance.md), the value used is in extra.resolved; \"preset\": as given");
        f("scale_rule_radius", scale_rule_radius, kScaleRuleRadiusDoc);
        f("relative_fitness", relative_fitness,
          "stop when the fitness change is below this (and the RMSE change too); 1e-6 = "
          "Open3D default");
        f("relative_rmse", relative_rmse,
          "stop when the inlier-RMSE change is below this (and the fitness change too) "
          "[unit-sphere units]: Open3D compares the absolute change; 1e-6 = Open3D default");
    }
    void Validate(ParamCheck& c) const {
        Open3dIcpOptions::Validate(c);
        c.Above("scale_rule_radius", scale_rule_radius, 0.0);
    }
};

AlignResult AlignIcp(const IcpOptions& o, const PointCloud& source, const PointCloud& target,
                     const AlignContext& /*context*/) {
    namespace o3r = open3d::pipelines::registration;
    const ScaleRule rule = ResolveScaleRule(source, target, o.scale_rule_radius);
    const double unit = o.scale_rule == ScaleRuleMode::kAuto ? rule.unit : 1.0;
    const double distance = o.max_correspondence_distance * unit;
    AlignResult result = RunOpen3dIcp(
        ToOpen3d(source), ToOpen3d(target), distance,
        o3r::TransformationEstimationPointToPoint(/*with_scaling=*/false), o.Criteria());
    result.extra["resolved"] = {{"max_correspondence_distance", distance},
                                {"scale_rule", rule.ToJson()}};
    return result;
}

}  // namespace

MethodInfo IcpMethodInfo() {
    MethodInfo info = MakeMethodInfo<IcpOptions>(
        "icp",
        "point-to-point ICP from the identity (Open3D RegistrationICP), Open3D/OGMM-code criteria",
        AlignIcp);
    info.paper_label = "ICP";  // the row of the OGMM paper's tables
    return info;
}

}  // namespace regbench
