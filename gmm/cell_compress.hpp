#pragma once
// Cell compression for Gaussian sums at scale: every point of a cloud is replaced by the
// weighted centroid of its cubic grid cell, carrying the cell's summed weight.
//
// Why it is accurate: for a Gaussian k(x) = exp(-|q - x|^2 / 2 sigma^2) the error of
// sum_{j in cell} w_j k(x_j) ~ W k(centroid) is second order in the members' spread around the
// weighted centroid (the first-order term cancels exactly), i.e. relative O((h / sigma)^2) for
// cell edge h. With h = kappa * sigma and kappa = 0.25 the worst-case term error is a few
// percent and the sums' error far smaller (docs/performance.md measures it), while the number
// of terms drops from N to ~ surface area / h^2, independent of N. Unlike Nystrom it never
// yields a negative kernel sum, and unlike the IFGT it needs no expansion order or clustering
// seed: the result is deterministic.
#include <Eigen/Core>

#include "core/point_cloud.hpp"

namespace regbench {

struct CellCompressed {
    PointCloud centroids;     ///< C x 3, weighted centroid of each occupied cell
    Eigen::VectorXd weights;  ///< C, summed member weights (counts when unweighted)
};

/// Merges `points` per cell of edge `cell` (> 0) on a grid anchored at the coordinate origin.
/// `weights` (same length as points, >= 0) or nullptr for all ones. Cells come out sorted by
/// cell index, so the result does not depend on the input order. A cell whose members all have
/// weight 0 keeps its plain centroid and weight 0. Throws std::invalid_argument naming the
/// problem for an empty cloud, a non-positive cell or a grid too fine to index (> 2^20 cells
/// per axis).
CellCompressed CompressToCells(const PointCloud& points, const Eigen::VectorXd* weights,
                               double cell);

}  // namespace regbench
