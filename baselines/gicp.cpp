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
#include "baselines/schemas.hpp"
#include "core/method_spec.hpp"

namespace regbench {
namespace {

struct GicpOptions {  // documented in baselines/gicp.schema.json (defaults too)
    double max_correspondence_distance;
    int max_iterations;
    double transformation_epsilon;
    double rotation_epsilon;
    int correspondence_randomness;
    int max_optimizer_iterations;
    double translation_gradient_tolerance;
    double rotation_gradient_tolerance;
};
// clang-format off
REGBENCH_OPTION_FIELDS(GicpOptions, max_correspondence_distance, max_iterations,
                       transformation_epsilon, rotation_epsilon, correspondence_randomness,
                       max_optimizer_iterations, translation_gradient_tolerance,
                       rotation_gradient_tolerance)
// clang-format on

using PclGicp = pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ>;

/// PCL keeps the iteration count protected; this exposes it.
class CountingGicp final : public PclGicp {
public:
    int Iterations() const { return nr_iterations_; }
};

AlignResult AlignGicp(const GicpOptions& o,
                      const PointCloud& source,
                      const PointCloud& target,
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
    CountingGicp gicp;
    gicp.setInputSource(ToPcl(source));
    gicp.setInputTarget(ToPcl(target));
    gicp.setMaxCorrespondenceDistance(o.max_correspondence_distance);
    gicp.setMaximumIterations(o.max_iterations);
    gicp.setTransformationEpsilon(o.transformation_epsilon);
    gicp.setRotationEpsilon(o.rotation_epsilon);
    gicp.setCorrespondenceRandomness(o.correspondence_randomness);
    gicp.setMaximumOptimizerIterations(o.max_optimizer_iterations);
    gicp.setTranslationGradientTolerance(o.translation_gradient_tolerance);
    gicp.setRotationGradientTolerance(o.rotation_gradient_tolerance);

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
    const double d = o.max_correspondence_distance;
    result.extra = {{"fitness_score", gicp.getFitnessScore(d * d)}};
    return result;
}

}  // namespace

MethodInfo GicpMethodInfo() {
    return MakeMethodInfo(SpecOf<GicpOptions>(BaselineSchema("gicp")), AlignGicp);
}

}  // namespace regbench
