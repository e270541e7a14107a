#include "baselines/ndt.hpp"

#include <pcl/registration/ndt.h>

#include <stdexcept>
#include <string>

#include "baselines/pcl_adapter.hpp"
#include "core/options.hpp"
#include "core/scale_rule.hpp"

namespace regbench {
namespace {

constexpr const char* kName = "ndt";

/// PCL's defaults are tuned for metre-scale lidar maps; the scale-dependent ones are
/// rescaled here for unit-sphere objects with ~717 points.
struct NdtOptions {
    /// Voxel side [unit-sphere units]: 0.25 leaves ~8x8x8 cells over the object, so a 70%
    /// crop of 717 points puts ~10-20 points (>= min_points_per_voxel) in an occupied cell.
    double resolution = 0.25;
    int min_points_per_voxel = 6;  ///< cells with fewer points get no Gaussian (PCL default)
    double step_size = 0.1;        ///< More-Thuente maximum step length (PCL default)
    double outlier_ratio = 0.55;   ///< uniform outlier mixture weight, Magnusson eq. 6.8 (PCL)
    int max_iterations = 35;       ///< Newton iteration cap (PCL default)
    /// Stop when the last step's squared translation is <= this (PCL semantics); 1e-6 means
    /// a 1e-3 step. PCL's 0.1 would stop a unit-scale object after its first step.
    double transformation_epsilon = 1e-6;
    /// ... and the cosine of the last step's rotation angle is >= this (0 disables):
    /// cos(1e-3 rad), so mostly-rotational steps about the centroid also count.
    double transformation_rotation_epsilon = 0.9999995;
    /// "auto": resolution (and the step size) times the pair's unit (core/scale_rule.hpp);
    /// "preset": as given
    std::string scale_rule = "auto";
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(NdtOptions,
                                                resolution,
                                                min_points_per_voxel,
                                                step_size,
                                                outlier_ratio,
                                                max_iterations,
                                                transformation_epsilon,
                                                transformation_rotation_epsilon,
                                                scale_rule)

void Validate(const NdtOptions& o) {
    Require(o.resolution > 0.0, kName, "resolution", "must be > 0");
    Require(o.min_points_per_voxel >= 3, kName, "min_points_per_voxel",
            "must be >= 3 (a covariance needs 3 points)");
    Require(o.step_size > 0.0, kName, "step_size", "must be > 0");
    Require(o.outlier_ratio >= 0.0 && o.outlier_ratio < 1.0, kName, "outlier_ratio",
            "must be in [0, 1)");
    Require(o.max_iterations >= 1, kName, "max_iterations", "must be >= 1");
    RequireOneOf(o.scale_rule, {"auto", "preset"}, kName, "scale_rule");
    Require(o.transformation_epsilon > 0.0, kName, "transformation_epsilon", "must be > 0");
    Require(o.transformation_rotation_epsilon >= 0.0 && o.transformation_rotation_epsilon < 1.0,
            kName, "transformation_rotation_epsilon", "must be in [0, 1)");
}

using PclNdt = pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ>;

/// Exposes whether the target voxel grid holds any Gaussian: PCL only prints an error and
/// returns the identity when it does not.
class CheckedNdt final : public PclNdt {
public:
    std::size_t TargetCells() { return target_cells_.getCentroids()->size(); }
};

class NdtMethod final : public RegistrationMethod {
public:
    explicit NdtMethod(NdtOptions options) : options_(options) {}
    std::string Name() const override { return kName; }
    nlohmann::json Params() const override { return options_; }

protected:
    AlignResult DoAlign(const PointCloud& source,
                        const PointCloud& target,
                        const AlignContext& /*context*/) override {
        const ScaleRule rule = ResolveScaleRule(source, target);
        const double unit = options_.scale_rule == "auto" ? rule.unit : 1.0;
        const double resolution = options_.resolution * unit;
        CheckedNdt ndt;
        // Order matters: PCL voxelises the target inside setInputTarget.
        ndt.setMinPointPerVoxel(static_cast<unsigned int>(options_.min_points_per_voxel));
        ndt.setResolution(static_cast<float>(resolution));
        ndt.setStepSize(options_.step_size * unit);
        ndt.setOulierRatio(options_.outlier_ratio);
        ndt.setMaximumIterations(options_.max_iterations);
        ndt.setTransformationEpsilon(options_.transformation_epsilon);
        ndt.setTransformationRotationEpsilon(options_.transformation_rotation_epsilon);
        ndt.setInputTarget(ToPcl(target));
        if (ndt.TargetCells() == 0) {
            throw std::runtime_error("no target voxel of side " + std::to_string(resolution) +
                                     " holds >= " + std::to_string(options_.min_points_per_voxel) +
                                     " points");
        }
        ndt.setInputSource(ToPcl(source));

        pcl::PointCloud<pcl::PointXYZ> aligned;
        ndt.align(aligned);

        AlignResult result;
        result.T_target_source = FromPclTransform(ndt.getFinalTransformation());
        result.iterations = ndt.getFinalNumIteration();
        if (result.iterations >= options_.max_iterations) {
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
                          {"step_size", options_.step_size * unit},
                          {"scale_rule", rule.ToJson()}}}};
        return result;
    }

private:
    NdtOptions options_;
};

}  // namespace

MethodInfo NdtMethodInfo() {
    MethodInfo info;
    info.name = kName;
    info.summary =
        "3-D Normal Distributions Transform from the identity (PCL NormalDistributionsTransform, "
        "float32), rescaled for unit-sphere objects";
    info.param_docs = {
        {"resolution",
         "target voxel side [unit-sphere units], > 0; 0.25: ~10-20 points per occupied cell of a "
         "717-point crop (PCL's 1.0 is metre-scale)"},
        {"min_points_per_voxel", "cells with fewer points are dropped, >= 3; 6 = PCL default"},
        {"scale_rule",
         "\"auto\": resolution and step_size scaled by the pair's unit (RMS radius / 0.6 when "
         "outside [0.5, 2], else 1; docs/performance.md), used values in extra.resolved; "
         "\"preset\": as given"},
        {"step_size", "More-Thuente maximum step length, > 0; 0.1 = PCL default"},
        {"outlier_ratio", "uniform outlier weight of the NDT mixture, [0, 1); 0.55 = PCL default"},
        {"max_iterations", "Newton iteration cap, >= 1; 35 = PCL default"},
        {"transformation_epsilon",
         "stop when the last step's squared translation is <= this, > 0; 1e-6 (a 1e-3 step; "
         "PCL's 0.1 is metre-scale)"},
        {"transformation_rotation_epsilon",
         "and when cos(last step's rotation angle) >= this, [0, 1), 0 disables; 0.9999995 = "
         "cos(1e-3 rad)"},
    };
    info.defaults = NdtOptions{};
    info.create = [](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        const auto options = ParseOptions<NdtOptions>(j, kName);
        Validate(options);
        return std::make_unique<NdtMethod>(options);
    };
    return info;
}

}  // namespace regbench
