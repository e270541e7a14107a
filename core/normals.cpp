#include "core/normals.hpp"

#include <Eigen/Eigenvalues>
#include <stdexcept>
#include <vector>

#include "core/kd_tree.hpp"

namespace regbench {

Normals EstimateNormals(const PointCloud& points, int k) {
    if (k < 3) throw std::invalid_argument("EstimateNormals: k must be >= 3");
    Normals normals = Normals::Zero(points.rows(), 3);
    if (points.rows() < 3) return normals;
    KdTree tree(points);
    const Eigen::Vector3d centroid = points.colwise().mean().transpose();
    std::vector<Eigen::Index> idx;
    std::vector<double> sq;
    for (Eigen::Index i = 0; i < points.rows(); ++i) {
        const Eigen::Vector3d p = points.row(i).transpose();
        tree.Knn(p, k, idx, sq);
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (auto j : idx) mean += points.row(j).transpose();
        mean /= static_cast<double>(idx.size());
        Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
        for (auto j : idx) {
            const Eigen::Vector3d d = points.row(j).transpose() - mean;
            cov += d * d.transpose();
        }
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
        Eigen::Vector3d n = eig.eigenvectors().col(0);
        if (n.dot(p - centroid) < 0.0) n = -n;
        normals.row(i) = n.transpose();
    }
    return normals;
}

}  // namespace regbench
