#include "baselines/open3d_adapter.hpp"

#include <vector>

namespace regbench {
namespace {

namespace o3r = open3d::pipelines::registration;

/// Forwards to another estimation and counts ComputeTransformation calls: RegistrationICP
/// calls it exactly once per iteration, so the count is the iteration count.
class CountingEstimation final : public o3r::TransformationEstimation {
public:
    explicit CountingEstimation(const o3r::TransformationEstimation& inner) : inner_(inner) {}
    o3r::TransformationEstimationType GetTransformationEstimationType() const override {
        return inner_.GetTransformationEstimationType();
    }
    double ComputeRMSE(const open3d::geometry::PointCloud& source,
                       const open3d::geometry::PointCloud& target,
                       const o3r::CorrespondenceSet& corres) const override {
        return inner_.ComputeRMSE(source, target, corres);
    }
    Eigen::Matrix4d ComputeTransformation(const open3d::geometry::PointCloud& source,
                                          const open3d::geometry::PointCloud& target,
                                          const o3r::CorrespondenceSet& corres) const override {
        ++calls_;
        if (corres.empty()) ++empty_calls_;
        return inner_.ComputeTransformation(source, target, corres);
    }
    int calls() const { return calls_; }
    int empty_calls() const { return empty_calls_; }

private:
    const o3r::TransformationEstimation& inner_;
    mutable int calls_ = 0;  // RegistrationICP takes the estimation by const reference
    mutable int empty_calls_ = 0;
};

}  // namespace

open3d::geometry::PointCloud ToOpen3d(const PointCloud& points) {
    open3d::geometry::PointCloud cloud;
    cloud.points_.resize(static_cast<std::size_t>(points.rows()));
    for (Eigen::Index i = 0; i < points.rows(); ++i) {
        cloud.points_[static_cast<std::size_t>(i)] = points.row(i).transpose();
    }
    return cloud;
}

AlignResult RunOpen3dIcp(const open3d::geometry::PointCloud& source,
                         const open3d::geometry::PointCloud& target,
                         double max_correspondence_distance,
                         const o3r::TransformationEstimation& estimation,
                         const o3r::ICPConvergenceCriteria& criteria) {
    const CountingEstimation counting(estimation);
    const o3r::RegistrationResult reg =
        o3r::RegistrationICP(source, target, max_correspondence_distance,
                             Eigen::Matrix4d::Identity(), counting, criteria);
    AlignResult result;
    result.T_target_source = reg.transformation_;
    result.iterations = counting.calls();
    // Open3D stops early only when both relative changes fall below their thresholds.
    if (counting.empty_calls() > 0 && reg.correspondence_set_.empty()) {
        result.stop_reason = "no_correspondences";
    } else if (counting.calls() < criteria.max_iteration_) {
        result.stop_reason = "converged";
    } else {
        result.stop_reason = "max_iterations";
    }
    result.extra = {{"fitness", reg.fitness_},
                    {"inlier_rmse", reg.inlier_rmse_},
                    {"correspondences", reg.correspondence_set_.size()}};
    return result;
}

}  // namespace regbench
