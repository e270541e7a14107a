#pragma once
// 3-D kd-tree over a PointCloud (nanoflann). The tree references the cloud: the cloud must
// outlive the tree and must not be modified while it exists.
#include <Eigen/Core>
#include <memory>
#include <utility>
#include <vector>

#include "core/point_cloud.hpp"

namespace regbench {

/// Thread-safety: queries are const and may run concurrently; construction may not.
class KdTree {
public:
    explicit KdTree(const PointCloud& points, int leaf_size = 10);
    ~KdTree();
    KdTree(const KdTree&) = delete;
    KdTree& operator=(const KdTree&) = delete;

    /// Index of and squared distance to the nearest point; (-1, inf) for an empty cloud.
    std::pair<Eigen::Index, double> Nearest(const Eigen::Vector3d& query) const;
    /// k nearest neighbours, closest first (fewer if the cloud is smaller).
    void Knn(const Eigen::Vector3d& query, int k, std::vector<Eigen::Index>& indices,
             std::vector<double>& sq_distances) const;
    /// All points within `radius` (not squared), sorted by distance.
    void Radius(const Eigen::Vector3d& query, double radius,
                std::vector<std::pair<Eigen::Index, double>>& index_sq_distance) const;
    Eigen::Index size() const { return points_.rows(); }
    const PointCloud& points() const { return points_; }

private:
    struct Impl;
    const PointCloud& points_;
    std::unique_ptr<Impl> impl_;
};

/// For every query point, the Euclidean distance to its nearest neighbour in `tree`.
Eigen::VectorXd NearestDistances(const KdTree& tree, const PointCloud& queries);

}  // namespace regbench
