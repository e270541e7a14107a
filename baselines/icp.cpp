#include "baselines/icp.hpp"

#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>

#include "baselines/open3d_adapter.hpp"
#include "core/options.hpp"
#include "core/scale_rule.hpp"

namespace regbench {
namespace {

constexpr const char* kName = "icp";

struct IcpOptions {
    /// Pairs farther apart are not correspondences. OGMM code: 2 * overlap_radius, with
    /// overlap_radius = 0.035 for ModelNet (unit-sphere objects).
    double max_correspondence_distance = 1.0;
    int max_iterations = 30;         ///< Open3D ICPConvergenceCriteria default, as OGMM
    double relative_fitness = 1e-6;  ///< stop when |fitness change| is below this ...
    double relative_rmse = 1e-6;     ///< ... and |inlier RMSE change| is below this
    /// "auto": max_correspondence_distance times the pair's unit (core/scale_rule.hpp; 1 for
    /// unit-sphere objects); "preset": as given
    std::string scale_rule = "auto";
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(IcpOptions,
                                                max_correspondence_distance,
                                                max_iterations,
                                                relative_fitness,
                                                relative_rmse,
                                                scale_rule)

void Validate(const IcpOptions& o) {
    Require(o.max_correspondence_distance > 0.0, kName, "max_correspondence_distance",
            "must be > 0");
    Require(o.max_iterations >= 1, kName, "max_iterations", "must be >= 1");
    RequireOneOf(o.scale_rule, {"auto", "preset"}, kName, "scale_rule");
    Require(o.relative_fitness >= 0.0, kName, "relative_fitness", "must be >= 0");
    Require(o.relative_rmse >= 0.0, kName, "relative_rmse", "must be >= 0");
}

class IcpMethod final : public RegistrationMethod {
public:
    explicit IcpMethod(IcpOptions options) : options_(options) {}
    std::string Name() const override { return kName; }
    nlohmann::json Params() const override { return options_; }

protected:
    AlignResult DoAlign(const PointCloud& source,
                        const PointCloud& target,
                        const AlignContext& /*context*/) override {
        namespace o3r = open3d::pipelines::registration;
        const o3r::ICPConvergenceCriteria criteria(options_.relative_fitness,
                                                   options_.relative_rmse, options_.max_iterations);
        const ScaleRule rule = ResolveScaleRule(source, target);
        const double unit = options_.scale_rule == "auto" ? rule.unit : 1.0;
        const double distance = options_.max_correspondence_distance * unit;
        AlignResult result = RunOpen3dIcp(
            ToOpen3d(source), ToOpen3d(target), distance,
            o3r::TransformationEstimationPointToPoint(/*with_scaling=*/false), criteria);
        result.extra["resolved"] = {{"max_correspondence_distance", distance},
                                    {"scale_rule", rule.ToJson()}};
        return result;
    }

private:
    IcpOptions options_;
};

}  // namespace

MethodInfo IcpMethodInfo() {
    MethodInfo info;
    info.name = kName;
    info.summary =
        "point-to-point ICP from the identity (Open3D RegistrationICP), Open3D/OGMM-code criteria";
    info.param_docs = {
        {"max_correspondence_distance",
         "pairs farther apart are ignored [unit-sphere units], > 0; 1.0 covers the protocols' "
         "motions (translation up to 0.5 per axis) from the identity; 0.07 = 2 * overlap_radius "
         "is the OGMM code's radius for refining a network's estimate, where ICP barely moves"},
        {"max_iterations", "iteration cap, >= 1; 30 = Open3D default, as the OGMM code"},
        {"scale_rule",
         "\"auto\": max_correspondence_distance is scaled by the pair's unit (RMS radius / 0.6 "
         "when outside [0.5, 2], else 1: unit-sphere objects keep the preset; "
         "docs/performance.md), the value used is in extra.resolved; \"preset\": as given"},
        {"relative_fitness",
         "stop when the fitness change is below this (and the RMSE change too), >= 0; 1e-6 = "
         "Open3D default"},
        {"relative_rmse",
         "stop when the inlier-RMSE change is below this (and the fitness change too), >= 0; "
         "1e-6 = Open3D default"},
    };
    info.defaults = IcpOptions{};
    info.create = [](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        const auto options = ParseOptions<IcpOptions>(j, kName);
        Validate(options);
        return std::make_unique<IcpMethod>(options);
    };
    return info;
}

}  // namespace regbench
