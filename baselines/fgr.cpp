#include "baselines/fgr.hpp"

#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/pipelines/registration/FastGlobalRegistration.h>
#include <open3d/pipelines/registration/Feature.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/utility/Random.h>

#include <chrono>
#include <memory>
#include <mutex>

#include "baselines/open3d_adapter.hpp"
#include "core/options.hpp"
#include "core/rng.hpp"
#include "core/scale_rule.hpp"

namespace regbench {
namespace {

constexpr const char* kName = "fgr";

/// Radii follow the Open3D tutorial (and the OGMM repo's unused FPFH helper) as multiples of
/// one voxel size; the FGR solver settings are Open3D's Python defaults.
struct FgrOptions {
    /// Base length: 0.05 is about the sample spacing sqrt(area / 1024) of a unit-sphere
    /// object (0.06 on the test object), so FPFH (5 voxels = 0.25) sees ~50-100 neighbours.
    double voxel_size = 0.05;
    bool voxel_downsample = false;  ///< tutorial downsamples dense scans; ours are already sparse
    double normal_radius_voxels = 2.0;                ///< normal radius = 2 * voxel (tutorial)
    int normal_max_nn = 30;                           ///< tutorial
    double fpfh_radius_voxels = 5.0;                  ///< FPFH radius = 5 * voxel (tutorial)
    int fpfh_max_nn = 100;                            ///< tutorial
    double max_correspondence_distance_voxels = 0.5;  ///< 0.5 * voxel (tutorial)
    double division_factor = 1.4;     ///< graduated non-convexity factor (Open3D default)
    bool use_absolute_scale = false;  ///< Open3D default: distances relative to object size
    bool decrease_mu = false;         ///< Open3D Python binding default
    int iteration_number = 64;        ///< Open3D default
    double tuple_scale = 0.95;        ///< tuple edge-length ratio test (Open3D default)
    int maximum_tuple_count = 1000;   ///< Open3D default
    bool tuple_test = true;           ///< Open3D default
    int seed = 0;                     ///< Open3D RNG seed set before each call (tuple sampling)
    /// "auto": voxel_size times the pair's unit, and voxel downsampling for clouds above 2048
    /// points (core/scale_rule.hpp); "preset": the values as given (the paper's setting)
    std::string scale_rule = "auto";
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(FgrOptions,
                                                voxel_size,
                                                voxel_downsample,
                                                normal_radius_voxels,
                                                normal_max_nn,
                                                fpfh_radius_voxels,
                                                fpfh_max_nn,
                                                max_correspondence_distance_voxels,
                                                division_factor,
                                                use_absolute_scale,
                                                decrease_mu,
                                                iteration_number,
                                                tuple_scale,
                                                maximum_tuple_count,
                                                tuple_test,
                                                seed,
                                                scale_rule)

void Validate(const FgrOptions& o) {
    Require(o.voxel_size > 0.0, kName, "voxel_size", "must be > 0");
    Require(o.normal_radius_voxels > 0.0, kName, "normal_radius_voxels", "must be > 0");
    Require(o.normal_max_nn >= 3, kName, "normal_max_nn", "must be >= 3");
    Require(o.fpfh_radius_voxels > 0.0, kName, "fpfh_radius_voxels", "must be > 0");
    Require(o.fpfh_max_nn >= 1, kName, "fpfh_max_nn", "must be >= 1");
    Require(o.max_correspondence_distance_voxels > 0.0, kName, "max_correspondence_distance_voxels",
            "must be > 0");
    Require(o.division_factor > 1.0, kName, "division_factor", "must be > 1");
    Require(o.iteration_number >= 1, kName, "iteration_number", "must be >= 1");
    Require(o.tuple_scale > 0.0 && o.tuple_scale < 1.0, kName, "tuple_scale", "must be in (0, 1)");
    Require(o.maximum_tuple_count >= 1, kName, "maximum_tuple_count", "must be >= 1");
    RequireOneOf(o.scale_rule, {"auto", "preset"}, kName, "scale_rule");
}

class FgrMethod final : public RegistrationMethod {
public:
    explicit FgrMethod(FgrOptions options) : options_(options) {}
    std::string Name() const override { return kName; }
    nlohmann::json Params() const override { return options_; }

protected:
    AlignResult DoAlign(const PointCloud& source,
                        const PointCloud& target,
                        const AlignContext& context) override {
        namespace o3r = open3d::pipelines::registration;
        const ScaleRule rule = ResolveScaleRule(source, target);
        const bool automatic = options_.scale_rule == "auto";
        const double voxel = options_.voxel_size * (automatic ? rule.unit : 1.0);
        const bool downsample = options_.voxel_downsample || (automatic && rule.dense);
        const auto source_o3d = Prepare(source, voxel, downsample);
        const auto target_o3d = Prepare(target, voxel, downsample);
        const auto source_fpfh = Fpfh(*source_o3d, voxel);
        const auto target_fpfh = Fpfh(*target_o3d, voxel);

        const o3r::FastGlobalRegistrationOption fgr_option(
            options_.division_factor, options_.use_absolute_scale, options_.decrease_mu,
            options_.max_correspondence_distance_voxels * voxel, options_.iteration_number,
            options_.tuple_scale, options_.maximum_tuple_count, options_.tuple_test);
        // The tuple test draws random triplets from Open3D's process-wide engine: seeding it and
        // drawing must not interleave with another thread's FGR (runner --jobs > 1), or results
        // depend on timing. Time spent waiting for the lock is excluded from the method's time.
        static std::mutex open3d_random_mutex;
        const auto wait_start = std::chrono::steady_clock::now();
        std::unique_lock<std::mutex> lock(open3d_random_mutex);
        const double waited =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - wait_start).count();
        // The per-pair stream (AlignContext) mixed with the user's seed: each pair draws its own
        // triplets, identically whatever the run's order or --jobs.
        open3d::utility::random::Seed(static_cast<int>(
            SplitMix64(context.MethodSeed() ^ static_cast<std::uint64_t>(options_.seed)) &
            0x7fffffffULL));
        const o3r::RegistrationResult reg = o3r::FastGlobalRegistrationBasedOnFeatureMatching(
            *source_o3d, *target_o3d, *source_fpfh, *target_fpfh, fgr_option);
        lock.unlock();

        AlignResult result;
        result.T_target_source = reg.transformation_;
        result.iterations = options_.iteration_number;  // FGR runs a fixed number
        result.stop_reason = "max_iterations";
        result.extra = {{"fitness", reg.fitness_},
                        {"inlier_rmse", reg.inlier_rmse_},
                        {"correspondences", reg.correspondence_set_.size()},
                        {"source_points_used", source_o3d->points_.size()},
                        {"target_points_used", target_o3d->points_.size()},
                        {"resolved",
                         {{"voxel_size", voxel},
                          {"voxel_downsample", downsample},
                          {"scale_rule", rule.ToJson()}}},
                        {kExcludedSecondsKey, waited}};
        return result;
    }

private:
    /// Optional voxel downsampling, then normals (FPFH needs them).
    std::shared_ptr<open3d::geometry::PointCloud> Prepare(const PointCloud& points,
                                                          double voxel,
                                                          bool downsample) const {
        auto cloud = std::make_shared<open3d::geometry::PointCloud>(ToOpen3d(points));
        if (downsample) cloud = cloud->VoxelDownSample(voxel);
        cloud->EstimateNormals(open3d::geometry::KDTreeSearchParamHybrid(
            options_.normal_radius_voxels * voxel, options_.normal_max_nn));
        return cloud;
    }

    std::shared_ptr<open3d::pipelines::registration::Feature> Fpfh(
        const open3d::geometry::PointCloud& cloud, double voxel) const {
        return open3d::pipelines::registration::ComputeFPFHFeature(
            cloud, open3d::geometry::KDTreeSearchParamHybrid(options_.fpfh_radius_voxels * voxel,
                                                             options_.fpfh_max_nn));
    }

    FgrOptions options_;
};

}  // namespace

MethodInfo FgrMethodInfo() {
    MethodInfo info;
    info.name = kName;
    info.summary =
        "Fast Global Registration on FPFH features (Open3D ComputeFPFHFeature + "
        "FastGlobalRegistrationBasedOnFeatureMatching), Open3D tutorial radii";
    info.param_docs = {
        {"voxel_size",
         "base length for the radii below [unit-sphere units], > 0; 0.05 ~ the sample spacing "
         "sqrt(area / 1024) of a unit-sphere object, so FPFH (0.25) sees 50-100 neighbours"},
        {"voxel_downsample",
         "voxel-downsample both clouds first (tutorial step for dense scans); false: 717 "
         "points are already at ~voxel spacing"},
        {"normal_radius_voxels", "normal radius in voxels, > 0; 2 = Open3D tutorial / OGMM helper"},
        {"normal_max_nn", "neighbour cap per normal, >= 3; 30 = Open3D tutorial / OGMM helper"},
        {"fpfh_radius_voxels", "FPFH radius in voxels, > 0; 5 = Open3D tutorial / OGMM helper"},
        {"fpfh_max_nn", "neighbour cap per FPFH, >= 1; 100 = Open3D tutorial / OGMM helper"},
        {"max_correspondence_distance_voxels",
         "FGR max correspondence distance in voxels (used for the mu floor when decrease_mu "
         "and for the reported fitness), > 0; 0.5 = Open3D tutorial"},
        {"division_factor", "graduated non-convexity divisor of mu, > 1; 1.4 = Open3D default"},
        {"use_absolute_scale",
         "measure distances absolutely instead of relative to the object size; false = "
         "Open3D default"},
        {"decrease_mu",
         "anneal mu by division_factor every 4 iterations; false = Open3D Python default"},
        {"iteration_number", "number of FGR iterations (fixed), >= 1; 64 = Open3D default"},
        {"tuple_scale", "tuple-test edge-length ratio, in (0, 1); 0.95 = Open3D default"},
        {"maximum_tuple_count", "tuples kept at most, >= 1; 1000 = Open3D default"},
        {"tuple_test", "run the tuple (geometric consistency) test; true = Open3D default"},
        {"seed", "seed for Open3D's global RNG, set right before each call (tuple sampling); 0"},
        {"scale_rule",
         "\"auto\": voxel_size scaled by the pair's unit (RMS radius / 0.6 when outside [0.5, "
         "2], else 1) and voxel downsampling when a cloud has > 2048 points "
         "(docs/performance.md); used values in extra.resolved; \"preset\": as given"},
    };
    info.defaults = FgrOptions{};
    info.create = [](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        const auto options = ParseOptions<FgrOptions>(j, kName);
        Validate(options);
        return std::make_unique<FgrMethod>(options);
    };
    return info;
}

}  // namespace regbench
