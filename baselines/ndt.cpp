#include "baselines/ndt.hpp"

#include <pcl/registration/ndt.h>

#include <stdexcept>
#include <string>

#include "baselines/pcl_adapter.hpp"
#include "core/params.hpp"
#include "core/scale_rule.hpp"

namespace regbench {
namespace {

/// PCL's defaults are tuned for metre-scale lidar maps; the scale-dependent ones are
/// rescaled here for unit-sphere objects with ~717 points.
struct NdtOptions {
    double resolution = 0.25;                         ///< target voxel side [unit-sphere units]
    int min_points_per_voxel = 6;                     ///< cells with fewer points are dropped
    ScaleRuleMode scale_rule = ScaleRuleMode::kAuto;  ///< "auto" or "preset"
    double scale_rule_radius = kScaleRuleReferenceRadius;  ///< [unit-sphere units]
    double step_size = 0.1;                           ///< More-Thuente maximum step length
    double outlier_ratio = 0.55;                      ///< uniform outlier weight of the NDT mixture
    int max_iterations = 35;                          ///< Newton iteration cap
    /// stop when the last step's squared translation is <= this
    double transformation_epsilon = 1e-6;
    /// and when cos(last step's rotation angle) >= this; 0 disables
    double transformation_rotation_epsilon = 0.9999995;

    template <class F>
    void Fields(F&& f) {
        f("resolution", resolution,
          "target voxel side [unit-sphere units]; 0.25: ~10-20 points per occupied cell of a "
          "717-point crop (PCL's 1.0 is metre-scale)");
        f("min_points_per_voxel", min_points_per_voxel,
          "cells with fewer points are dropped; 6 = PCL default");
        f("scale_rule", scale_rule,
          "\"auto\": resolution and step_size scaled by the pair's unit u (RMS radius / 0.6 "
          "when outside [0.5, 2], else 1; docs/performance.md), transformation_epsilon (a "
          "squared length) by u^2, used values in extra.resolved; \"preset\": as given");
        f("scale_rule_radius", scale_rule_radius, kScaleRuleRadiusDoc);
        f("step_size", step_size,
          "More-Thuente maximum step length [unit-sphere units]; 0.1 = PCL default");
        f("outlier_ratio", outlier_ratio,
          "uniform outlier weight of the NDT mixture; 0.55 = PCL default");
        f("max_iterations", max_iterations, "Newton iteration cap; 35 = PCL default");
        f("transformation_epsilon", transformation_epsilon,
          "stop when the last step's squared translation is <= this [unit-sphere units^2]; "
          "1e-6 (a 1e-3 step; "
          "PCL's 0.1 is metre-scale)");
        f("transformation_rotation_epsilon", transformation_rotation_epsilon,
          "and when cos(last step's rotation angle) >= this; 0 disables; 0.9999995 = "
          "cos(1e-3 rad)");
    }
    void Validate(ParamCheck& c) const {
        c.Above("resolution", resolution, 0.0);
        c.Above("scale_rule_radius", scale_rule_radius, 0.0);
        c.AtLeast("min_points_per_voxel", min_points_per_voxel, 3);
        c.Above("step_size", step_size, 0.0);
        c.AtLeast("outlier_ratio", outlier_ratio, 0.0);
        c.Below("outlier_ratio", outlier_ratio, 1.0);
        c.AtLeast("max_iterations", max_iterations, 1);
        c.Above("transformation_epsilon", transformation_epsilon, 0.0);
        c.AtLeast("transformation_rotation_epsilon", transformation_rotation_epsilon, 0.0);
        c.Below("transformation_rotation_epsilon", transformation_rotation_epsilon, 1.0);
    }
    /// Scale guard class: voxel grid, near-linear.
    CostClass Cost() const { return CostClass::kNearLinear; }
};

using PclNdt = pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ>;

/// Exposes whether the target voxel grid holds any Gaussian: PCL only prints an error and
/// returns the identity when it does not.
class CheckedNdt final : public PclNdt {
public:
    std::size_t TargetCells() { return target_cells_.getCentroids()->size(); }
};

AlignResult AlignNdt(const NdtOptions& o, const PointCloud& source, const PointCloud& target,
                     const AlignContext& /*context*/) {
    const ScaleRule rule = ResolveScaleRule(source, target, o.scale_rule_radius);
    const double unit = o.scale_rule == ScaleRuleMode::kAuto ? rule.unit : 1.0;
    const double resolution = o.resolution * unit;
    CheckedNdt ndt;
    // Order matters: PCL voxelises the target inside setInputTarget.
    ndt.setMinPointPerVoxel(static_cast<unsigned int>(o.min_points_per_voxel));
    ndt.setResolution(static_cast<float>(resolution));
    ndt.setStepSize(o.step_size * unit);
    ndt.setOulierRatio(o.outlier_ratio);
    ndt.setMaximumIterations(o.max_iterations);
    ndt.setTransformationEpsilon(o.transformation_epsilon * unit * unit);  // a squared length
    ndt.setTransformationRotationEpsilon(o.transformation_rotation_epsilon);
    ndt.setInputTarget(ToPcl(target));
    if (ndt.TargetCells() == 0) {
        throw std::runtime_error("no target voxel of side " + std::to_string(resolution) +
                                 " holds >= " + std::to_string(o.min_points_per_voxel) + " points");
    }
    ndt.setInputSource(ToPcl(source));

    pcl::PointCloud<pcl::PointXYZ> aligned;
    ndt.align(aligned);

    AlignResult result;
    result.T_target_source = FromPclTransform(ndt.getFinalTransformation());
    result.iterations = ndt.getFinalNumIteration();
    if (result.iterations >= o.max_iterations) {
        result.stop_reason = "max_iterations";
    } else if (ndt.hasConverged()) {
        result.stop_reason = "converged";
    } else {
        result.stop_reason = "no_step";  // PCL: NaN Newton step, returns where it was
    }
    // PCL returns before its first step when the Newton step at the input is exactly zero,
    // which happens when no source point scores against any target cell (likelihood 0): the
    // input is then far from aligned and NDT made no progress, so this is no result.
    if (result.iterations == 0 && ndt.getTransformationLikelihood() == 0.0) {
        result.status = AlignStatus::kFailed;
        result.stop_reason = "no_progress";
        result.message = "ndt: 0 iterations: no source point lies near a target cell of side " +
                         std::to_string(resolution) + " (likelihood 0), so NDT returned its input";
    }
    result.extra = {{"transformation_likelihood", ndt.getTransformationLikelihood()},
                    {"target_cells", ndt.TargetCells()},
                    {"resolved",
                     {{"resolution", resolution},
                      {"step_size", o.step_size * unit},
                      {"scale_rule", rule.ToJson()}}}};
    return result;
}

}  // namespace

MethodInfo NdtMethodInfo() {
    return MakeMethodInfo<NdtOptions>(
        "ndt",
        "3-D Normal Distributions Transform from the identity (PCL NormalDistributionsTransform, "
        "float32), rescaled for unit-sphere objects",
        AlignNdt);
}

}  // namespace regbench
