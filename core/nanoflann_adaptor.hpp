#pragma once
// The nanoflann dataset adaptor over a PointCloud, shared by KdTree and the kernel sums.
#include <cstddef>
#include <nanoflann.hpp>

#include "core/point_cloud.hpp"

namespace regbench {

/// nanoflann dataset adaptor over a row-major N x 3 matrix. It references the cloud: the
/// cloud must outlive every index built on it.
struct CloudAdaptor {
    const PointCloud& points;
    std::size_t kdtree_get_point_count() const { return static_cast<std::size_t>(points.rows()); }
    double kdtree_get_pt(std::size_t i, std::size_t dim) const {
        return points(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(dim));
    }
    template <class BBox>
    bool kdtree_get_bbox(BBox&) const {
        return false;
    }
};

/// Static 3-D L2 kd-tree over a CloudAdaptor.
using CloudKdTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, CloudAdaptor>,
                                        CloudAdaptor, 3, std::size_t>;

}  // namespace regbench
