#include "baselines/ndt.hpp"

#include <pcl/registration/ndt.h>

#include <stdexcept>
#include <string>

#include "baselines/pcl_adapter.hpp"
#include "baselines/schemas.hpp"
#include "core/method_spec.hpp"
#include "core/scale_rule.hpp"

namespace regbench {
namespace {

/// PCL's defaults are tuned for metre-scale lidar maps; the scale-dependent ones are
/// rescaled here for unit-sphere objects with ~717 points.
struct NdtOptions {  // documented in baselines/ndt.schema.json (defaults too)
    double resolution;
    int min_points_per_voxel;
    double step_size;
    double outlier_ratio;
    int max_iterations;
    double transformation_epsilon;
    double transformation_rotation_epsilon;
    ScaleRuleMode scale_rule;
};
// clang-format off
REGBENCH_OPTION_FIELDS(NdtOptions, resolution, min_points_per_voxel, step_size, outlier_ratio,
                       max_iterations, transformation_epsilon, transformation_rotation_epsilon,
                       scale_rule)
// clang-format on

using PclNdt = pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ>;

/// Exposes whether the target voxel grid holds any Gaussian: PCL only prints an error and
/// returns the identity when it does not.
class CheckedNdt final : public PclNdt {
public:
    std::size_t TargetCells() { return target_cells_.getCentroids()->size(); }
};

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
    // PCL returns before its first step when the Newton step at the input is exactly zero,
    // which happens when no source point scores against any target cell (likelihood 0): the
    // input is then far from aligned and NDT made no progress, so this is no result.
    if (result.iterations == 0 && ndt.getTransformationLikelihood() == 0.0) {
        result.status = AlignStatus::kFailed;
        result.stop_reason = "no_progress";
        result.message =
            "ndt: 0 iterations: no source point lies near a target cell of side " +
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
    return MakeMethodInfo(SpecOf<NdtOptions>(BaselineSchema("ndt")), AlignNdt);
}

}  // namespace regbench
