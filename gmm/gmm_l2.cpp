#include "gmm/gmm_l2.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/kd_tree.hpp"
#include "core/math_constants.hpp"
#include "core/transform.hpp"
#include "gmm/cell_compress.hpp"
#include "gmm/gmm_common.hpp"
#include "gmm/simd_exp.hpp"

namespace regbench {
namespace {

/// Below this many Gaussian pairs per evaluation one thread is faster (thread start-up
/// dominates; measured: threads hurt tiny problems).
constexpr double kMinPairsPerThread = 1.0e5;

struct RowSums {
    double s0, s1x, s1y, s1z;
};

/// s0 = sum_j w_j e_j, s1 = sum_j w_j e_j mu_j with e_j = exp(-|x - mu_j|^2 / 2 sigma^2).
/// Compiled twice (AVX2+FMA and baseline); the loop vectorises via `omp simd`.
REGBENCH_SIMD_CLONES RowSums GaussRowSums(double x, double y, double z, const double* tx,
                                          const double* ty, const double* tz, const double* tw,
                                          long n, double neg_inv_two_sigma2) {
    double s0 = 0.0, s1x = 0.0, s1y = 0.0, s1z = 0.0;
#pragma omp simd reduction(+ : s0, s1x, s1y, s1z)
    for (long j = 0; j < n; ++j) {
        const double dx = x - tx[j];
        const double dy = y - ty[j];
        const double dz = z - tz[j];
        const double we = tw[j] * ExpClamped((dx * dx + dy * dy + dz * dz) * neg_inv_two_sigma2);
        s0 += we;
        s1x += we * tx[j];
        s1y += we * ty[j];
        s1z += we * tz[j];
    }
    return {s0, s1x, s1y, s1z};
}

/// GaussRowSums over only the target components within `radius` of x (kd-tree radius search,
/// gathered in distance order into per-thread SoA buffers so the sum still vectorises).
RowSums CutoffRowSums(const KdTree& tree, double radius, const Eigen::Vector3d& x, const double* tx,
                      const double* ty, const double* tz, const double* tw,
                      double neg_inv_two_sigma2) {
    thread_local std::vector<std::pair<Eigen::Index, double>> found;
    thread_local std::vector<double> gx, gy, gz, gw;
    tree.Radius(x, radius, found);
    const size_t n = found.size();
    gx.resize(n);
    gy.resize(n);
    gz.resize(n);
    gw.resize(n);
    for (size_t k = 0; k < n; ++k) {
        const auto j = static_cast<size_t>(found[k].first);
        gx[k] = tx[j];
        gy[k] = ty[j];
        gz[k] = tz[j];
        gw[k] = tw[j];
    }
    return GaussRowSums(x[0], x[1], x[2], gx.data(), gy.data(), gz.data(), gw.data(),
                        static_cast<long>(n), neg_inv_two_sigma2);
}

}  // namespace

Eigen::Matrix3d RotationFromQuaternionWxyz(const Eigen::Vector4d& q) {
    const double nq = q.squaredNorm();
    if (nq < 1e-300) return Eigen::Matrix3d::Identity();
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    Eigen::Matrix3d A;                                    // R = I + (2 / |q|^2) A(q)
    A << -(y * y + z * z), x * y - w * z, x * z + w * y,  //
        x * y + w * z, -(x * x + z * z), y * z - w * x,   //
        x * z - w * y, y * z + w * x, -(x * x + y * y);
    return Eigen::Matrix3d::Identity() + (2.0 / nq) * A;
}

std::array<Eigen::Matrix3d, 4> RotationDerivativeFromQuaternionWxyz(const Eigen::Vector4d& q) {
    const double nq = q.squaredNorm();
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    Eigen::Matrix3d A;
    A << -(y * y + z * z), x * y - w * z, x * z + w * y,  //
        x * y + w * z, -(x * x + z * z), y * z - w * x,   //
        x * z - w * y, y * z + w * x, -(x * x + y * y);
    std::array<Eigen::Matrix3d, 4> dA;
    dA[0] << 0, -z, y, z, 0, -x, -y, x, 0;
    dA[1] << 0, y, z, y, -2 * x, -w, z, w, -2 * x;
    dA[2] << -2 * y, x, w, x, 0, z, -w, z, -2 * y;
    dA[3] << -2 * z, -w, x, w, -2 * z, y, x, y, 0;
    // d/dq_k [(2 / |q|^2) A] = (2 / |q|^2) dA_k - (4 q_k / |q|^4) A.
    std::array<Eigen::Matrix3d, 4> dR;
    for (int k = 0; k < 4; ++k) dR[k] = (2.0 / nq) * dA[k] - (4.0 * q[k] / (nq * nq)) * A;
    return dR;
}

Transform TransformFromTheta(const Eigen::VectorXd& theta) {
    return MakeTransform(RotationFromQuaternionWxyz(theta.head<4>()), theta.segment<3>(4));
}

Eigen::VectorXd RigidGmmL2Cost::InitialTheta() {
    Eigen::VectorXd theta = Eigen::VectorXd::Zero(7);
    theta[0] = 1.0;
    return theta;
}

double CutoffRadiusSigmas(double tolerance) {
    if (!(tolerance > 0.0 && tolerance < 1.0)) {
        throw std::invalid_argument("cutoff tolerance must be in (0, 1), got " +
                                    std::to_string(tolerance));
    }
    return std::sqrt(2.0 * std::log(1.0 / tolerance));
}

RigidGmmL2Cost::~RigidGmmL2Cost() = default;

RigidGmmL2Cost::RigidGmmL2Cost(const MixtureFeatures& source, const MixtureFeatures& target,
                               double sigma, L2Gradient gradient, double cutoff_radius)
    : source_means_(source.means),
      source_weights_(source.weights),
      sigma_(sigma),
      gradient_(gradient),
      cutoff_radius_(cutoff_radius),
      target_means_(target.means) {
    if (!(cutoff_radius > 0.0)) {
        throw std::invalid_argument("RigidGmmL2Cost: cutoff radius must be positive");
    }
    if (std::isfinite(cutoff_radius)) tree_ = std::make_unique<KdTree>(target_means_);
    if (!(sigma > 0.0) || !std::isfinite(sigma)) {
        throw std::invalid_argument("RigidGmmL2Cost: sigma must be positive and finite");
    }
    if (source.means.rows() != source.weights.size() ||
        target.means.rows() != target.weights.size()) {
        throw std::invalid_argument("RigidGmmL2Cost: means and weights differ in length");
    }
    const double z = std::pow(2.0 * kPi * sigma * sigma, 1.5);  // Z = (2 pi sigma^2)^(D/2)
    tx_ = target.means.col(0);
    ty_ = target.means.col(1);
    tz_ = target.means.col(2);
    tw_ = target.weights / z;
}

double RigidGmmL2Cost::operator()(const Eigen::VectorXd& theta, Eigen::VectorXd& grad) const {
    const Eigen::Vector4d q = theta.head<4>();
    const Eigen::Matrix3d R = RotationFromQuaternionWxyz(q);
    const Eigen::Vector3d t = theta.segment<3>(4);
    const long ns = static_cast<long>(source_means_.rows());
    const long nt = static_cast<long>(tx_.size());
    const double neg_inv_two_sigma2 = -0.5 / (sigma_ * sigma_);
    // probreg divides by 2 sigma^2 where d/dx exp(-|x - mu|^2 / 2 sigma^2) gives sigma^2.
    const double grad_scale =
        gradient_ == L2Gradient::kExact ? 1.0 / (sigma_ * sigma_) : 0.5 / (sigma_ * sigma_);

    std::vector<double> f_rows(static_cast<size_t>(ns));
    PointCloud g_rows(ns, 3);
    const bool parallel =
        static_cast<double>(ns) * static_cast<double>(nt) >= 2 * kMinPairsPerThread;
#pragma omp parallel for schedule(static) if (parallel)
    for (long i = 0; i < ns; ++i) {
        const Eigen::Vector3d x = R * source_means_.row(i).transpose() + t;
        const RowSums s = tree_ ? CutoffRowSums(*tree_, cutoff_radius_, x, tx_.data(), ty_.data(),
                                                tz_.data(), tw_.data(), neg_inv_two_sigma2)
                                : GaussRowSums(x[0], x[1], x[2], tx_.data(), ty_.data(), tz_.data(),
                                               tw_.data(), nt, neg_inv_two_sigma2);
        const double phi = source_weights_[i];
        f_rows[static_cast<size_t>(i)] = -phi * s.s0;
        // g_i = phi_i sum_j (phi_j / Z) e_ij (x_i - mu_j) * grad_scale
        g_rows.row(i) =
            (phi * grad_scale) * (s.s0 * x - Eigen::Vector3d(s.s1x, s.s1y, s.s1z)).transpose();
    }
    double f = 0.0;
    Eigen::Vector3d g_t = Eigen::Vector3d::Zero();
    Eigen::Matrix3d M = Eigen::Matrix3d::Zero();  // sum_i g_i mu_s_i^T = d f / d R
    for (long i = 0; i < ns; ++i) {
        f += f_rows[static_cast<size_t>(i)];
        g_t += g_rows.row(i).transpose();
        M += g_rows.row(i).transpose() * source_means_.row(i);
    }
    const std::array<Eigen::Matrix3d, 4> dR = RotationDerivativeFromQuaternionWxyz(q);
    grad.resize(7);
    for (int k = 0; k < 4; ++k) grad[k] = (M.array() * dR[k].array()).sum();
    grad.segment<3>(4) = g_t;
    return f;
}

L2Frame L2Frame::CenteredScaled(const PointCloud& source, const PointCloud& target, double scale) {
    if (!(scale > 0.0) || !std::isfinite(scale)) {
        throw std::invalid_argument("L2Frame: scale must be positive and finite");
    }
    L2Frame f;
    f.source_center = source.colwise().mean().transpose();
    f.target_center = target.colwise().mean().transpose();
    f.scale = scale;
    return f;
}

PointCloud L2Frame::SourceIn(const PointCloud& source) const {
    return (source.rowwise() - source_center.transpose()) / scale;
}

PointCloud L2Frame::TargetIn(const PointCloud& target) const {
    return (target.rowwise() - target_center.transpose()) / scale;
}

Transform L2Frame::ToInput(const Transform& T_frame) const {
    // x = c_t + s (R (y - c_s) / s + t') = R y + (c_t + s t' - R c_s)
    const Eigen::Matrix3d R = T_frame.topLeftCorner<3, 3>();
    const Eigen::Vector3d t =
        target_center + scale * T_frame.topRightCorner<3, 1>() - R * source_center;
    return MakeTransform(R, t);
}

MixtureFeatures CompressMixture(const MixtureFeatures& mixture, double cell) {
    const CellCompressed c = CompressToCells(mixture.means, &mixture.weights, cell);
    return {c.centroids, c.weights};
}

L2SumsPlan PlanL2Sums(const MixtureFeatures& source, const MixtureFeatures& target, double sigma,
                      const L2SumOptions& sums) {
    L2SumsPlan plan{source, target};
    const double pairs =
        static_cast<double>(source.means.rows()) * static_cast<double>(target.means.rows());
    if (sums.kernel_sums == L2KernelSums::kDense || pairs < sums.min_pairs) return plan;
    if (sums.compress_cell_sigmas > 0.0) {
        // The source is compressed in its own frame: it moves rigidly, cells stay cells.
        const double cell = sums.compress_cell_sigmas * sigma;
        MixtureFeatures s = CompressMixture(source, cell);
        if (2 * s.means.rows() <= source.means.rows()) {
            plan.source = std::move(s);
            plan.compressed_source = true;
        }
        MixtureFeatures t = CompressMixture(target, cell);
        if (2 * t.means.rows() <= target.means.rows()) {
            plan.target = std::move(t);
            plan.compressed_target = true;
        }
    }
    const double radius = sigma * CutoffRadiusSigmas(sums.cutoff_tolerance);
    const Eigen::Vector3d extent = target.means.colwise().maxCoeff().transpose() -
                                   target.means.colwise().minCoeff().transpose();
    if (radius < 0.25 * extent.norm()) plan.cutoff_radius = radius;
    return plan;
}

BfgsResult MinimizeRigidL2(const MixtureFeatures& source, const MixtureFeatures& target,
                           double sigma, L2Gradient gradient, const Eigen::VectorXd& theta0,
                           const BfgsOptions& options, const L2SumOptions& sums,
                           bool* approximated) {
    const L2SumsPlan plan = PlanL2Sums(source, target, sigma, sums);
    if (approximated != nullptr) *approximated = plan.approximated();
    const RigidGmmL2Cost cost(plan.source, plan.target, sigma, gradient, plan.cutoff_radius);
    return MinimizeBfgs(
        [&cost](const Eigen::VectorXd& theta, Eigen::VectorXd& grad) { return cost(theta, grad); },
        theta0, options);
}

AnnealedL2Result MinimizeAnnealedL2(MixtureFeatures& source, MixtureFeatures& target, double sigma,
                                    const AnnealedL2Options& options, const RefitMixtures& refit) {
    AnnealedL2Result fit;
    fit.theta = RigidGmmL2Cost::InitialTheta();
    double f_prev = 0.0;
    int outer = 0;
    for (outer = 1; outer <= options.outer_iterations; ++outer) {
        if (refit) refit(sigma, source, target);
        bool approximated = false;
        fit.last = MinimizeRigidL2(source, target, sigma, options.gradient, fit.theta, options.bfgs,
                                   options.sums, &approximated);
        fit.approximated = fit.approximated || approximated;
        fit.iterations += fit.last.iterations;
        fit.theta = fit.last.x;
        sigma *= options.delta;
        if (outer > 1 && std::abs(fit.last.f - f_prev) < options.outer_tol) break;
        f_prev = fit.last.f;
    }
    fit.outer_steps = std::min(outer, options.outer_iterations);
    return fit;
}

AlignResult AnnealedL2AlignResult(const L2Frame& frame, const AnnealedL2Result& fit) {
    AlignResult result;
    result.T_target_source = frame.ToInput(TransformFromTheta(fit.theta));
    result.iterations = fit.iterations;
    result.stop_reason = fit.last.stop_reason;
    result.extra = Convergence{fit.iterations, fit.last.f, fit.last.stop_reason}.ToJson();
    result.extra["outer_iterations"] = fit.outer_steps;
    result.extra["evaluations"] = fit.last.evaluations;
    result.extra["approximated_sums"] = fit.approximated;
    return result;
}

}  // namespace regbench
