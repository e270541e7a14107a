#include "baselines/pcl_adapter.hpp"

#include <Eigen/SVD>

namespace regbench {

pcl::PointCloud<pcl::PointXYZ>::Ptr ToPcl(const PointCloud& points) {
    auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    cloud->resize(static_cast<std::size_t>(points.rows()));
    for (Eigen::Index i = 0; i < points.rows(); ++i) {
        auto& p = (*cloud)[static_cast<std::size_t>(i)];
        p.x = static_cast<float>(points(i, 0));
        p.y = static_cast<float>(points(i, 1));
        p.z = static_cast<float>(points(i, 2));
    }
    return cloud;
}

Transform FromPclTransform(const Eigen::Matrix4f& T) {
    Transform out = T.cast<double>();
    // Nearest rotation in the Frobenius norm: U diag(1, 1, det(U V^T)) V^T.
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(out.topLeftCorner<3, 3>(),
                                                Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Vector3d d(1.0, 1.0, (svd.matrixU() * svd.matrixV().transpose()).determinant());
    out.topLeftCorner<3, 3>() = svd.matrixU() * d.asDiagonal() * svd.matrixV().transpose();
    out.row(3) << 0.0, 0.0, 0.0, 1.0;
    return out;
}

}  // namespace regbench
