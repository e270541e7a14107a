#include "networks/families/deepgmr/rri.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/kd_tree.hpp"

namespace regbench::networks {

namespace {

constexpr double kTwoPi = 6.283185307179586;

/// Features of one point p given its k neighbours (centred coordinates).
void PointFeatures(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& nbrs,
                   RriVariant variant, double* out) {
    const int k = static_cast<int>(nbrs.size());
    const double rp = p.norm();
    const Eigen::Vector3d p_hat = p / rp;
    std::vector<Eigen::Vector3d> tangent(k);
    for (int j = 0; j < k; ++j) {
        const double rq = nbrs[j].norm();
        const double d = std::clamp(p_hat.dot(nbrs[j]) / rq, -1.0, 1.0);
        // The original's "projection" q - d p is scaled by |p|, not the orthogonal projection;
        // only its direction in the plane matters for phi, so this is kept as is.
        tangent[j] = nbrs[j] - d * p;
        out[4 * j + 0] = rp;
        out[4 * j + 1] = rq;
        out[4 * j + 2] = std::acos(d);
    }
    for (int j = 0; j < k; ++j) {
        double phi = std::numeric_limits<double>::infinity();
        for (int m = 0; m < k; ++m) {
            if (m == j) continue;
            const Eigen::Vector3d cross = variant == RriVariant::kCuda
                                              ? tangent[j].cross(tangent[m])
                                              : tangent[m].cross(tangent[j]);
            double psi = std::atan2(cross.dot(p_hat), tangent[j].dot(tangent[m]));
            if (psi < 0) psi += kTwoPi;
            phi = std::min(phi, psi);
        }
        out[4 * j + 3] = phi;
    }
}

}  // namespace

Eigen::MatrixXd RriFeatures(const PointCloud& cloud, int k, RriVariant variant) {
    if (k < 2) throw std::invalid_argument("RriFeatures: k must be >= 2, got " + std::to_string(k));
    if (cloud.rows() < k + 1) {
        throw std::invalid_argument("RriFeatures: cloud has " + std::to_string(cloud.rows()) +
                                    " points, need >= k + 1 = " + std::to_string(k + 1));
    }
    const PointCloud centred = cloud.rowwise() - cloud.colwise().mean();
    const KdTree tree(centred);
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rows(centred.rows(),
                                                                                4 * k);
    std::vector<Eigen::Index> idx;
    std::vector<double> d2;
    std::vector<Eigen::Vector3d> nbrs(k);
    for (Eigen::Index i = 0; i < centred.rows(); ++i) {
        const Eigen::Vector3d p = centred.row(i).transpose();
        tree.Knn(p, k + 1, idx, d2);
        for (int j = 0; j < k; ++j) nbrs[j] = centred.row(idx[j + 1]).transpose();  // drop self
        PointFeatures(p, nbrs, variant, rows.row(i).data());
    }
    return rows;
}

torch::Tensor RriFeatureTensor(const torch::Tensor& xyz, int k, RriVariant variant) {
    TORCH_CHECK(xyz.dim() == 3 && xyz.size(2) == 3, "RriFeatureTensor: expected xyz [B,N,3]");
    torch::NoGradGuard no_grad;
    const torch::Tensor cpu = xyz.detach().to(torch::kCPU, torch::kDouble).contiguous();
    const int64_t b = cpu.size(0);
    const int64_t n = cpu.size(1);
    torch::Tensor out = torch::empty({b, n, 4 * k}, torch::kDouble);
    for (int64_t s = 0; s < b; ++s) {
        const PointCloud cloud = Eigen::Map<const PointCloud>(cpu[s].data_ptr<double>(), n, 3);
        const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> f =
            RriFeatures(cloud, k, variant);
        std::copy(f.data(), f.data() + f.size(), out[s].data_ptr<double>());
    }
    return out.transpose(1, 2).contiguous().to(xyz.device(), torch::kFloat);
}

}  // namespace regbench::networks
