#include "baselines/gicp.hpp"

// GCC 12 reports a false -Warray-bounds inside Eigen's SSE loads instantiated by PCL's
// TransformationEstimationSVD (a 3-vector read as 4 floats); silence it for PCL's headers only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Warray-bounds"
#include <pcl/registration/gicp.h>
#pragma GCC diagnostic pop

#include <stdexcept>
#include <string>

#include "baselines/pcl_adapter.hpp"
#include "core/params.hpp"
#include "core/scale_rule.hpp"

namespace regbench {
namespace {

struct GicpOptions {
    /// pairs farther apart are ignored [unit-sphere units]
    double max_correspondence_distance = 1.0;
    int max_iterations = 200;  ///< outer iteration cap
    /// stop when every translation entry changes less than this
    double transformation_epsilon = 0.0005;
    /// stop when every rotation-matrix entry changes less than this
    double rotation_epsilon = 0.002;
    /// k nearest neighbours per point covariance (clouds need >= k points)
    int correspondence_randomness = 20;
    int max_optimizer_iterations = 20;             ///< BFGS iterations per outer step
    double translation_gradient_tolerance = 0.01;  ///< BFGS translation gradient stop
    double rotation_gradient_tolerance = 0.01;     ///< BFGS rotation gradient stop
    ScaleRuleMode scale_rule = ScaleRuleMode::kAuto;  ///< "auto" or "preset"
    double scale_rule_radius = kScaleRuleReferenceRadius;  ///< [unit-sphere units]

    template <class F>
    void Fields(F&& f) {
        f("max_correspondence_distance", max_correspondence_distance,
          "pairs farther apart are ignored [unit-sphere units]; 1.0 as `icp` (covers the "
          "protocols' motions from the identity)");
        f("max_iterations", max_iterations, "outer iteration cap; 200 = PCL default");
        f("transformation_epsilon", transformation_epsilon,
          "stop when every translation entry changes less than this [unit-sphere units]; "
          "5e-4 = PCL default (0.05% of the object radius)");
        f("rotation_epsilon", rotation_epsilon,
          "stop when every rotation-matrix entry changes less than this; 2e-3 = PCL default");
        f("correspondence_randomness", correspondence_randomness,
          "k nearest neighbours per point covariance (clouds need >= k points); 20 = PCL "
          "default (Segal et al.)");
        f("max_optimizer_iterations", max_optimizer_iterations,
          "BFGS iterations per outer step; 20 = PCL default");
        f("translation_gradient_tolerance", translation_gradient_tolerance,
          "BFGS translation gradient stop [unit-sphere units] (the cost is a squared "
          "length); 1e-2 = PCL");
        f("rotation_gradient_tolerance", rotation_gradient_tolerance,
          "BFGS rotation gradient stop [unit-sphere units^2] (the cost is a squared length); "
          "1e-2 = PCL");
        f("scale_rule", scale_rule,
          "\"auto\": as `icp`, the lengths scaled by the pair's unit u (RMS radius / 0.6 when "
          "outside [0.5, 2], else 1; docs/performance.md): max_correspondence_distance and "
          "transformation_epsilon times u, the gradient stops times u (translation) and u^2 "
          "(rotation: the cost is a squared length), used values in extra.resolved; "
          "\"preset\": as given");
        f("scale_rule_radius", scale_rule_radius, kScaleRuleRadiusDoc);
    }
    void Validate(ParamCheck& c) const {
        c.Above("max_correspondence_distance", max_correspondence_distance, 0.0);
        c.Above("scale_rule_radius", scale_rule_radius, 0.0);
        c.AtLeast("max_iterations", max_iterations, 1);
        c.Above("transformation_epsilon", transformation_epsilon, 0.0);
        c.Above("rotation_epsilon", rotation_epsilon, 0.0);
        c.AtLeast("correspondence_randomness", correspondence_randomness, 3);
        c.AtLeast("max_optimizer_iterations", max_optimizer_iterations, 1);
        c.Above("translation_gradient_tolerance", translation_gradient_tolerance, 0.0);
        c.Above("rotation_gradient_tolerance", rotation_gradient_tolerance, 0.0);
    }
    /// Scale guard class: kd-tree searches, near-linear.
    CostClass Cost() const { return CostClass::kNearLinear; }
};

using PclGicp = pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ>;

/// PCL keeps the iteration count protected; this exposes it.
class CountingGicp final : public PclGicp {
public:
    int Iterations() const { return nr_iterations_; }
};

AlignResult AlignGicp(const GicpOptions& o, const PointCloud& source, const PointCloud& target,
                      const AlignContext& /*context*/) {
    // PCL indexes an empty covariance vector (undefined behaviour) when a cloud has
    // fewer points than k, so refuse that here.
    const Eigen::Index k = o.correspondence_randomness;
    if (source.rows() < k || target.rows() < k) {
        throw std::invalid_argument("each cloud needs >= correspondence_randomness (" +
                                    std::to_string(k) + ") points, got source " +
                                    std::to_string(source.rows()) + ", target " +
                                    std::to_string(target.rows()));
    }
    const ScaleRule rule = ResolveScaleRule(source, target, o.scale_rule_radius);
    const double unit = o.scale_rule == ScaleRuleMode::kAuto ? rule.unit : 1.0;
    const double distance = o.max_correspondence_distance * unit;
    CountingGicp gicp;
    gicp.setInputSource(ToPcl(source));
    gicp.setInputTarget(ToPcl(target));
    gicp.setMaxCorrespondenceDistance(distance);
    gicp.setMaximumIterations(o.max_iterations);
    gicp.setTransformationEpsilon(o.transformation_epsilon * unit);
    gicp.setRotationEpsilon(o.rotation_epsilon);
    gicp.setCorrespondenceRandomness(o.correspondence_randomness);
    gicp.setMaximumOptimizerIterations(o.max_optimizer_iterations);
    gicp.setTranslationGradientTolerance(o.translation_gradient_tolerance * unit);
    gicp.setRotationGradientTolerance(o.rotation_gradient_tolerance * unit * unit);

    pcl::PointCloud<pcl::PointXYZ> aligned;
    gicp.align(aligned);

    AlignResult result;
    result.T_target_source = FromPclTransform(gicp.getFinalTransformation());
    result.iterations = gicp.Iterations();
    // PCL sets converged on the epsilon test and on the iteration cap; it leaves it unset
    // when the BFGS step throws (e.g. fewer than 4 correspondences within range).
    if (!gicp.hasConverged()) {
        // An internal error is no result, whatever transform PCL left behind.
        result.stop_reason = "optimizer_error";
        result.status = AlignStatus::kFailed;
        result.message =
            "gicp: optimizer_error: PCL's BFGS step failed after " +
            std::to_string(result.iterations) +
            " iteration(s) (e.g. fewer than 4 correspondences within max_correspondence_distance)";
    } else if (result.iterations >= o.max_iterations) {
        result.stop_reason = "max_iterations";
    } else {
        result.stop_reason = "converged";
    }
    // PCL's fitness: mean squared NN distance over points whose *squared* distance is
    // within the bound, hence the square.
    result.extra = {{"fitness_score", gicp.getFitnessScore(distance * distance)},
                    {"resolved",
                     {{"max_correspondence_distance", distance}, {"scale_rule", rule.ToJson()}}}};
    return result;
}

}  // namespace

MethodInfo GicpMethodInfo() {
    return MakeMethodInfo<GicpOptions>(
        "gicp", "Generalized-ICP from the identity (PCL GeneralizedIterativeClosestPoint, float32)",
        AlignGicp);
}

}  // namespace regbench
