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
#include "core/options.hpp"

namespace regbench {
namespace {

constexpr const char* kName = "gicp";

struct GicpOptions {
    /// As `icp` (OGMM: 2 * overlap_radius) so the ICP family differs only in the cost;
    /// PCL's default 5 would be unbounded at unit-sphere scale.
    double max_correspondence_distance = 1.0;
    int max_iterations = 200;              ///< outer ICP iterations (PCL default)
    double transformation_epsilon = 5e-4;  ///< stop: translation entries change < this (PCL)
    double rotation_epsilon = 2e-3;        ///< ... and rotation entries change < this (PCL)
    int correspondence_randomness = 20;    ///< k neighbours per covariance (PCL, Segal et al.)
    int max_optimizer_iterations = 20;     ///< BFGS iterations per outer step (PCL default)
    double translation_gradient_tolerance = 1e-2;  ///< BFGS stop (PCL default)
    double rotation_gradient_tolerance = 1e-2;     ///< BFGS stop (PCL default)
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(GicpOptions,
                                                max_correspondence_distance,
                                                max_iterations,
                                                transformation_epsilon,
                                                rotation_epsilon,
                                                correspondence_randomness,
                                                max_optimizer_iterations,
                                                translation_gradient_tolerance,
                                                rotation_gradient_tolerance)

void Validate(const GicpOptions& o) {
    Require(o.max_correspondence_distance > 0.0, kName, "max_correspondence_distance",
            "must be > 0");
    Require(o.max_iterations >= 1, kName, "max_iterations", "must be >= 1");
    Require(o.transformation_epsilon > 0.0, kName, "transformation_epsilon", "must be > 0");
    Require(o.rotation_epsilon > 0.0, kName, "rotation_epsilon", "must be > 0");
    Require(o.correspondence_randomness >= 3, kName, "correspondence_randomness",
            "must be >= 3 (a covariance needs 3 points)");
    Require(o.max_optimizer_iterations >= 1, kName, "max_optimizer_iterations", "must be >= 1");
    Require(o.translation_gradient_tolerance > 0.0, kName, "translation_gradient_tolerance",
            "must be > 0");
    Require(o.rotation_gradient_tolerance > 0.0, kName, "rotation_gradient_tolerance",
            "must be > 0");
}

using PclGicp = pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ>;

/// PCL keeps the iteration count protected; this exposes it.
class CountingGicp final : public PclGicp {
public:
    int Iterations() const { return nr_iterations_; }
};

class GicpMethod final : public RegistrationMethod {
public:
    explicit GicpMethod(GicpOptions options) : options_(options) {}
    std::string Name() const override { return kName; }
    nlohmann::json Params() const override { return options_; }

protected:
    AlignResult DoAlign(const PointCloud& source,
                        const PointCloud& target,
                        const AlignContext& /*context*/) override {
        // PCL indexes an empty covariance vector (undefined behaviour) when a cloud has
        // fewer points than k, so refuse that here.
        const Eigen::Index k = options_.correspondence_randomness;
        if (source.rows() < k || target.rows() < k) {
            throw std::invalid_argument("each cloud needs >= correspondence_randomness (" +
                                        std::to_string(k) + ") points, got source " +
                                        std::to_string(source.rows()) + ", target " +
                                        std::to_string(target.rows()));
        }
        CountingGicp gicp;
        gicp.setInputSource(ToPcl(source));
        gicp.setInputTarget(ToPcl(target));
        gicp.setMaxCorrespondenceDistance(options_.max_correspondence_distance);
        gicp.setMaximumIterations(options_.max_iterations);
        gicp.setTransformationEpsilon(options_.transformation_epsilon);
        gicp.setRotationEpsilon(options_.rotation_epsilon);
        gicp.setCorrespondenceRandomness(options_.correspondence_randomness);
        gicp.setMaximumOptimizerIterations(options_.max_optimizer_iterations);
        gicp.setTranslationGradientTolerance(options_.translation_gradient_tolerance);
        gicp.setRotationGradientTolerance(options_.rotation_gradient_tolerance);

        pcl::PointCloud<pcl::PointXYZ> aligned;
        gicp.align(aligned);

        AlignResult result;
        result.T_target_source = FromPclTransform(gicp.getFinalTransformation());
        result.iterations = gicp.Iterations();
        // PCL sets converged on the epsilon test and on the iteration cap; it leaves it unset
        // when the BFGS step throws (e.g. fewer than 4 correspondences within range).
        if (!gicp.hasConverged()) {
            result.stop_reason = "optimizer_error";
        } else if (result.iterations >= options_.max_iterations) {
            result.stop_reason = "max_iterations";
        } else {
            result.stop_reason = "converged";
        }
        // PCL's fitness: mean squared NN distance over points whose *squared* distance is
        // within the bound, hence the square.
        const double d = options_.max_correspondence_distance;
        result.extra = {{"fitness_score", gicp.getFitnessScore(d * d)}};
        return result;
    }

private:
    GicpOptions options_;
};

}  // namespace

MethodInfo GicpMethodInfo() {
    MethodInfo info;
    info.name = kName;
    info.summary =
        "Generalized-ICP from the identity (PCL GeneralizedIterativeClosestPoint, float32)";
    info.param_docs = {
        {"max_correspondence_distance",
         "pairs farther apart are ignored [unit-sphere units], > 0; 1.0 as `icp` (covers the "
         "protocols' motions from the identity)"},
        {"max_iterations", "outer iteration cap, >= 1; 200 = PCL default"},
        {"transformation_epsilon",
         "stop when every translation entry changes less than this, > 0; 5e-4 = PCL default "
         "(0.05% of the object radius)"},
        {"rotation_epsilon",
         "stop when every rotation-matrix entry changes less than this, > 0; 2e-3 = PCL "
         "default"},
        {"correspondence_randomness",
         "k nearest neighbours per point covariance, >= 3 (clouds need >= k points); 20 = "
         "PCL default (Segal et al.)"},
        {"max_optimizer_iterations", "BFGS iterations per outer step, >= 1; 20 = PCL default"},
        {"translation_gradient_tolerance", "BFGS translation gradient stop, > 0; 1e-2 = PCL"},
        {"rotation_gradient_tolerance", "BFGS rotation gradient stop, > 0; 1e-2 = PCL"},
    };
    info.defaults = GicpOptions{};
    info.create = [](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        const auto options = ParseOptions<GicpOptions>(j, kName);
        Validate(options);
        return std::make_unique<GicpMethod>(options);
    };
    return info;
}

}  // namespace regbench
