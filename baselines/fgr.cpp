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
#include "baselines/schemas.hpp"
#include "core/method_spec.hpp"
#include "core/rng.hpp"
#include "core/scale_rule.hpp"

namespace regbench {
namespace {

/// Radii follow the Open3D tutorial (and the OGMM repo's unused FPFH helper) as multiples of
/// one voxel size; the FGR solver settings are Open3D's Python defaults.
struct FgrOptions {  // documented in baselines/fgr.schema.json (defaults too)
    double voxel_size;
    bool voxel_downsample;
    double normal_radius_voxels;
    int normal_max_nn;
    double fpfh_radius_voxels;
    int fpfh_max_nn;
    double max_correspondence_distance_voxels;
    double division_factor;
    bool use_absolute_scale;
    bool decrease_mu;
    int iteration_number;
    double tuple_scale;
    int maximum_tuple_count;
    bool tuple_test;
    int seed;
    ScaleRuleMode scale_rule;
};
// clang-format off
REGBENCH_OPTION_FIELDS(FgrOptions, voxel_size, voxel_downsample, normal_radius_voxels, normal_max_nn,
                       fpfh_radius_voxels, fpfh_max_nn, max_correspondence_distance_voxels,
                       division_factor, use_absolute_scale, decrease_mu, iteration_number,
                       tuple_scale, maximum_tuple_count, tuple_test, seed, scale_rule)
// clang-format on

/// Optional voxel downsampling, then normals (FPFH needs them).
std::shared_ptr<open3d::geometry::PointCloud> Prepare(const FgrOptions& o,
                                                      const PointCloud& points,
                                                      double voxel,
                                                      bool downsample) {
    auto cloud = std::make_shared<open3d::geometry::PointCloud>(ToOpen3d(points));
    if (downsample) cloud = cloud->VoxelDownSample(voxel);
    cloud->EstimateNormals(
        open3d::geometry::KDTreeSearchParamHybrid(o.normal_radius_voxels * voxel, o.normal_max_nn));
    return cloud;
}

std::shared_ptr<open3d::pipelines::registration::Feature> Fpfh(
    const FgrOptions& o, const open3d::geometry::PointCloud& cloud, double voxel) {
    return open3d::pipelines::registration::ComputeFPFHFeature(
        cloud,
        open3d::geometry::KDTreeSearchParamHybrid(o.fpfh_radius_voxels * voxel, o.fpfh_max_nn));
}

AlignResult AlignFgr(const FgrOptions& o,
                     const PointCloud& source,
                     const PointCloud& target,
                     const AlignContext& context) {
    namespace o3r = open3d::pipelines::registration;
    const ScaleRule rule = ResolveScaleRule(source, target);
    const bool automatic = o.scale_rule == ScaleRuleMode::kAuto;
    const double voxel = o.voxel_size * (automatic ? rule.unit : 1.0);
    const bool downsample = o.voxel_downsample || (automatic && rule.dense);
    const auto source_o3d = Prepare(o, source, voxel, downsample);
    const auto target_o3d = Prepare(o, target, voxel, downsample);
    const auto source_fpfh = Fpfh(o, *source_o3d, voxel);
    const auto target_fpfh = Fpfh(o, *target_o3d, voxel);

    const o3r::FastGlobalRegistrationOption fgr_option(
        o.division_factor, o.use_absolute_scale, o.decrease_mu,
        o.max_correspondence_distance_voxels * voxel, o.iteration_number, o.tuple_scale,
        o.maximum_tuple_count, o.tuple_test);
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
        SplitMix64(context.MethodSeed() ^ static_cast<std::uint64_t>(o.seed)) & 0x7fffffffULL));
    const o3r::RegistrationResult reg = o3r::FastGlobalRegistrationBasedOnFeatureMatching(
        *source_o3d, *target_o3d, *source_fpfh, *target_fpfh, fgr_option);
    lock.unlock();

    AlignResult result;
    result.T_target_source = reg.transformation_;
    result.iterations = o.iteration_number;  // FGR runs a fixed number
    result.stop_reason = "max_iterations";
    result.extra = {
        {"fitness", reg.fitness_},
        {"inlier_rmse", reg.inlier_rmse_},
        {"correspondences", reg.correspondence_set_.size()},
        {"source_points_used", source_o3d->points_.size()},
        {"target_points_used", target_o3d->points_.size()},
        {"resolved",
         {{"voxel_size", voxel}, {"voxel_downsample", downsample}, {"scale_rule", rule.ToJson()}}},
        {kExcludedSecondsKey, waited}};
    return result;
}

}  // namespace

MethodInfo FgrMethodInfo() {
    return MakeMethodInfo(SpecOf<FgrOptions>(BaselineSchema("fgr")), AlignFgr);
}

}  // namespace regbench
