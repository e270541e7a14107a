#include "baselines/ndt.hpp"

#include <pcl/registration/ndt.h>

#include <stdexcept>
#include <string>

#include "baselines/pcl_adapter.hpp"
#include "core/method_spec.hpp"
#include "core/scale_rule.hpp"

namespace regbench {
namespace {

constexpr const char* kName = "ndt";

/// PCL's defaults are tuned for metre-scale lidar maps; the scale-dependent ones are
/// rescaled here for unit-sphere objects with ~717 points.
struct NdtOptions {  // each member documented once, in Spec()
    double resolution = 0.25;
    int min_points_per_voxel = 6;
    double step_size = 0.1;
    double outlier_ratio = 0.55;
    int max_iterations = 35;
    double transformation_epsilon = 1e-6;
    double transformation_rotation_epsilon = 0.9999995;
    ScaleRuleMode scale_rule = ScaleRuleMode::kAuto;
};

using PclNdt = pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ>;

/// Exposes whether the target voxel grid holds any Gaussian: PCL only prints an error and
/// returns the identity when it does not.
class CheckedNdt final : public PclNdt {
public:
    std::size_t TargetCells() { return target_cells_.getCentroids()->size(); }
};

const MethodSpec<NdtOptions>& Spec() {
    static const MethodSpec<NdtOptions> spec{
        kName,
        "3-D Normal Distributions Transform from the identity (PCL NormalDistributionsTransform, "
        "float32), rescaled for unit-sphere objects",
        {
            Param("resolution", &NdtOptions::resolution,
                  "target voxel side [unit-sphere units], > 0; 0.25: ~10-20 points per occupied "
                  "cell of a 717-point crop (PCL's 1.0 is metre-scale)")
                .Greater(0.0),
            Param("min_points_per_voxel", &NdtOptions::min_points_per_voxel,
                  "cells with fewer points are dropped, >= 3; 6 = PCL default")
                .AtLeast(3),
            Param("scale_rule", &NdtOptions::scale_rule,
                  "\"auto\": resolution and step_size scaled by the pair's unit (RMS radius / 0.6 "
                  "when outside [0.5, 2], else 1; docs/performance.md), used values in "
                  "extra.resolved; \"preset\": as given"),
            Param("step_size", &NdtOptions::step_size,
                  "More-Thuente maximum step length, > 0; 0.1 = PCL default")
                .Greater(0.0),
            Param("outlier_ratio", &NdtOptions::outlier_ratio,
                  "uniform outlier weight of the NDT mixture, [0, 1); 0.55 = PCL default")
                .AtLeast(0.0)
                .Below(1.0),
            Param("max_iterations", &NdtOptions::max_iterations,
                  "Newton iteration cap, >= 1; 35 = PCL default")
                .AtLeast(1),
            Param("transformation_epsilon", &NdtOptions::transformation_epsilon,
                  "stop when the last step's squared translation is <= this, > 0; 1e-6 (a 1e-3 "
                  "step; PCL's 0.1 is metre-scale)")
                .Greater(0.0),
            Param("transformation_rotation_epsilon", &NdtOptions::transformation_rotation_epsilon,
                  "and when cos(last step's rotation angle) >= this, [0, 1), 0 disables; 0.9999995 "
                  "= cos(1e-3 rad)")
                .AtLeast(0.0)
                .Below(1.0),
        },
        nullptr,
        {}};
    return spec;
}

AlignResult AlignNdt(const NdtOptions& o,
                     const PointCloud& source,
                     const PointCloud& target,
                     const AlignContext& /*context*/) {
    const ScaleRule rule = ResolveScaleRule(source, target);
    const double unit = o.scale_rule == ScaleRuleMode::kAuto ? rule.unit : 1.0;
    const double resolution = o.resolution * unit;
    CheckedNdt ndt;
    // Order matters: PCL voxelises the target inside setInputTarget.
    ndt.setMinPointPerVoxel(static_cast<unsigned int>(o.min_points_per_voxel));
    ndt.setResolution(static_cast<float>(resolution));
    ndt.setStepSize(o.step_size * unit);
    ndt.setOulierRatio(o.outlier_ratio);
    ndt.setMaximumIterations(o.max_iterations);
    ndt.setTransformationEpsilon(o.transformation_epsilon);
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
    result.extra = {{"transformation_likelihood", ndt.getTransformationLikelihood()},
                    {"target_cells", ndt.TargetCells()},
                    {"resolved",
                     {{"resolution", resolution},
                      {"step_size", o.step_size * unit},
                      {"scale_rule", rule.ToJson()}}}};
    return result;
}

}  // namespace

MethodInfo NdtMethodInfo() { return MakeMethodInfo(Spec(), AlignNdt); }

}  // namespace regbench
