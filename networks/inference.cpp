#include "networks/inference.hpp"

#include <torch/torch.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <stdexcept>
#include <string>

#include "networks/gemm_floor.hpp"
#include "networks/net.hpp"

namespace regbench::networks {
namespace {

torch::Tensor ToTensor(const PointCloud& cloud) {
    torch::Tensor t = torch::empty({1, cloud.rows(), 3}, torch::kDouble);
    std::copy(cloud.data(), cloud.data() + cloud.size(), t.data_ptr<double>());
    return t.to(torch::kFloat);
}

Transform ToRigidTransform(const torch::Tensor& T) {
    const torch::Tensor c = T.detach().to(torch::kCPU, torch::kDouble).contiguous();
    Eigen::Matrix<double, 4, 4, Eigen::RowMajor> m;
    std::copy(c.data_ptr<double>(), c.data_ptr<double>() + 16, m.data());
    Transform out = m;
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(out.topLeftCorner<3, 3>(),
                                                Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
    out.topLeftCorner<3, 3>() = svd.matrixU() * D * svd.matrixV().transpose();
    out.row(3) << 0.0, 0.0, 0.0, 1.0;
    return out;
}

}  // namespace

PairEstimate EstimatePair(RegistrationNet& net, const PointCloud& source, const PointCloud& target,
                          std::uint64_t seed, int threads) {
    torch::set_num_threads(std::max(1, threads));
    // torch's thread count does not reach an OpenBLAS built with pthreads, which would run
    // the GEMMs on every core beside the calling thread's clock.
    SetBlasThreads(threads);
    torch::NoGradGuard no_grad;
    PairBatch batch;
    batch.source = ToTensor(source);
    batch.target = ToTensor(target);
    batch.generator = at::detail::createCPUGenerator(seed);
    NetOutput out;
    try {
        out = net.Forward(batch);
    } catch (const c10::Error& e) {  // the message without LibTorch's stack dump
        throw std::runtime_error(std::string("the network failed: ") +
                                 e.what_without_backtrace());
    }
    // A NaN or Inf in the estimate is a failed call, never a transform made rigid (the SVD of
    // a NaN rotation came out as the identity and the row said ok).
    if (!torch::isfinite(out.T).all().item<bool>()) {
        throw std::runtime_error("the network's output transform is not finite (NaN or Inf)");
    }
    // RGM's assignment turns NaN scores into some permutation and Kabsch into a finite
    // transform: the NaN shows only in its intermediate outputs.
    for (const auto& [key, value] : out.aux) {
        if (value.defined() && value.is_floating_point() &&
            !torch::isfinite(value).all().item<bool>()) {
            throw std::runtime_error("the network's output " + key +
                                     " is not finite (NaN or Inf)");
        }
    }
    PairEstimate e;
    e.T = ToRigidTransform(out.T[0]);
    for (const auto& [key, value] : out.aux) {
        if (value.dim() == 2 && value.size(0) == 1 && value.size(1) == source.rows()) {
            e.source_point_means[key] = value.mean().item<double>();
        }
    }
    return e;
}

}  // namespace regbench::networks
