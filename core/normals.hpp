#pragma once
// Normal estimation by local PCA.
#include "core/point_cloud.hpp"

namespace regbench {

/// Unit normals from the smallest-eigenvalue eigenvector of each point's k-neighbourhood
/// covariance, oriented away from the cloud's centroid (objects) for repeatability.
/// Throws std::invalid_argument for k < 3.
Normals EstimateNormals(const PointCloud& points, int k = 30);

}  // namespace regbench
