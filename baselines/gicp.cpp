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
#include "core/method_spec.hpp"

namespace regbench {
namespace {

constexpr const char* kName = "gicp";

struct GicpOptions {  // each member documented once, in Spec()
    double max_correspondence_distance = 1.0;
    int max_iterations = 200;
    double transformation_epsilon = 5e-4;
    double rotation_epsilon = 2e-3;
    int correspondence_randomness = 20;
    int max_optimizer_iterations = 20;
    double translation_gradient_tolerance = 1e-2;
    double rotation_gradient_tolerance = 1e-2;
};

using PclGicp = pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ>;

/// PCL keeps the iteration count protected; this exposes it.
class CountingGicp final : public PclGicp {
public:
    int Iterations() const { return nr_iterations_; }
};

const MethodSpec<GicpOptions>& Spec() {
    static const MethodSpec<GicpOptions> spec{
        kName,
        "Generalized-ICP from the identity (PCL GeneralizedIterativeClosestPoint, float32)",
        {
            Param("max_correspondence_distance", &GicpOptions::max_correspondence_distance,
                  "pairs farther apart are ignored [unit-sphere units], > 0; 1.0 as `icp` (covers "
                  "the protocols' motions from the identity)")
                .Greater(0.0),
            Param("max_iterations", &GicpOptions::max_iterations,
                  "outer iteration cap, >= 1; 200 = PCL default")
                .AtLeast(1),
            Param("transformation_epsilon", &GicpOptions::transformation_epsilon,
                  "stop when every translation entry changes less than this, > 0; 5e-4 = PCL "
                  "default (0.05% of the object radius)")
                .Greater(0.0),
            Param("rotation_epsilon", &GicpOptions::rotation_epsilon,
                  "stop when every rotation-matrix entry changes less than this, > 0; 2e-3 = PCL "
                  "default")
                .Greater(0.0),
            Param("correspondence_randomness", &GicpOptions::correspondence_randomness,
                  "k nearest neighbours per point covariance, >= 3 (clouds need >= k points); 20 = "
                  "PCL default (Segal et al.)")
                .AtLeast(3),
            Param("max_optimizer_iterations", &GicpOptions::max_optimizer_iterations,
                  "BFGS iterations per outer step, >= 1; 20 = PCL default")
                .AtLeast(1),
            Param("translation_gradient_tolerance", &GicpOptions::translation_gradient_tolerance,
                  "BFGS translation gradient stop, > 0; 1e-2 = PCL")
                .Greater(0.0),
            Param("rotation_gradient_tolerance", &GicpOptions::rotation_gradient_tolerance,
                  "BFGS rotation gradient stop, > 0; 1e-2 = PCL")
                .Greater(0.0),
        },
        nullptr,
        {}};
    return spec;
}

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
        result.stop_reason = "optimizer_error";
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

MethodInfo GicpMethodInfo() { return MakeMethodInfo(Spec(), AlignGicp); }

}  // namespace regbench
