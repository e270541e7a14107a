#include "baselines/icp_pl.hpp"

#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>

#include "baselines/open3d_adapter.hpp"
#include "core/options.hpp"

namespace regbench {
namespace {

constexpr const char* kName = "icp-pl";

struct IcpPlOptions {
    double max_correspondence_distance = 1.0;  ///< as `icp`
    int max_iterations = 30;                   ///< Open3D ICPConvergenceCriteria default
    double relative_fitness = 1e-6;            ///< Open3D default
    double relative_rmse = 1e-6;               ///< Open3D default
    /// Normal neighbourhood radius: 2 * voxel with voxel 0.05 (Open3D tutorial recipe, the
    /// same as `fgr`), i.e. about twice the sample spacing of a unit-sphere object.
    double normal_radius = 0.1;
    int normal_max_nn = 30;  ///< at most this many neighbours per normal (Open3D tutorial)
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(IcpPlOptions,
                                                max_correspondence_distance,
                                                max_iterations,
                                                relative_fitness,
                                                relative_rmse,
                                                normal_radius,
                                                normal_max_nn)

void Validate(const IcpPlOptions& o) {
    Require(o.max_correspondence_distance > 0.0, kName, "max_correspondence_distance",
            "must be > 0");
    Require(o.max_iterations >= 1, kName, "max_iterations", "must be >= 1");
    Require(o.relative_fitness >= 0.0, kName, "relative_fitness", "must be >= 0");
    Require(o.relative_rmse >= 0.0, kName, "relative_rmse", "must be >= 0");
    Require(o.normal_radius > 0.0, kName, "normal_radius", "must be > 0");
    Require(o.normal_max_nn >= 3, kName, "normal_max_nn", "must be >= 3 (a plane needs 3)");
}

class IcpPlMethod final : public RegistrationMethod {
public:
    explicit IcpPlMethod(IcpPlOptions options) : options_(options) {}
    std::string Name() const override { return kName; }
    nlohmann::json Params() const override { return options_; }

protected:
    AlignResult DoAlign(const PointCloud& source,
                        const PointCloud& target,
                        const AlignContext& /*context*/) override {
        namespace o3r = open3d::pipelines::registration;
        // Point-to-plane (Chen & Medioni 1992) minimises distances along the target's normals,
        // so only the target needs them.
        open3d::geometry::PointCloud target_o3d = ToOpen3d(target);
        target_o3d.EstimateNormals(open3d::geometry::KDTreeSearchParamHybrid(
            options_.normal_radius, options_.normal_max_nn));
        const o3r::ICPConvergenceCriteria criteria(options_.relative_fitness,
                                                   options_.relative_rmse, options_.max_iterations);
        return RunOpen3dIcp(ToOpen3d(source), target_o3d, options_.max_correspondence_distance,
                            o3r::TransformationEstimationPointToPlane(), criteria);
    }

private:
    IcpPlOptions options_;
};

}  // namespace

MethodInfo IcpPlMethodInfo() {
    MethodInfo info;
    info.name = kName;
    info.summary =
        "point-to-plane ICP from the identity (Open3D RegistrationICP), target normals by "
        "Open3D EstimateNormals (hybrid radius/kNN)";
    info.param_docs = {
        {"max_correspondence_distance",
         "pairs farther apart are ignored [unit-sphere units], > 0; 1.0 as `icp`, so the two "
         "ICPs differ only in the cost"},
        {"max_iterations", "iteration cap, >= 1; 30 = Open3D default, as `icp`"},
        {"relative_fitness", "stop threshold on the fitness change, >= 0; 1e-6 = Open3D default"},
        {"relative_rmse", "stop threshold on the inlier-RMSE change, >= 0; 1e-6 = Open3D default"},
        {"normal_radius",
         "target-normal neighbourhood radius, > 0; 0.1 = 2 * voxel (0.05), Open3D tutorial "
         "recipe, ~2x the sample spacing of a unit-sphere object"},
        {"normal_max_nn", "neighbour cap per normal, >= 3; 30 = Open3D tutorial recipe"},
    };
    info.defaults = IcpPlOptions{};
    info.create = [](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        const auto options = ParseOptions<IcpPlOptions>(j, kName);
        Validate(options);
        return std::make_unique<IcpPlMethod>(options);
    };
    return info;
}

}  // namespace regbench
