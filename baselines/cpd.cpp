#include "baselines/cpd.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "core/kabsch.hpp"
#include "core/math_constants.hpp"
#include "core/transform.hpp"
#include "gmm/cell_compress.hpp"
#include "gmm/gauss_sum.hpp"
#include "gmm/gmm_common.hpp"

namespace regbench {

namespace {
Eigen::Vector3d Centroid(const PointCloud& cloud) {
    if (cloud.rows() == 0) throw std::invalid_argument("CpdEStep: target cloud is empty");
    return cloud.colwise().mean().transpose();
}
}  // namespace

CpdEStep::CpdEStep(const PointCloud& source, const PointCloud& target, GaussSumOptions options)
    : options_(options),
      source_points_(source),
      target_points_(target),
      source_(source, Centroid(target)),
      target_blocked_(target, Centroid(target)) {
    if (!(options_.truncation_sigmas > 0.0)) {
        throw std::invalid_argument("CpdEStep: truncation_sigmas must be positive");
    }
}

bool CpdEStep::CompressionPays(Eigen::Index cells, Eigen::Index points) const {
    return static_cast<double>(cells) < options_.cluster_max_fraction * static_cast<double>(points);
}

namespace {
/// Float weights in a BlockedCloud's stored order from per-input-row weights.
std::vector<float> StoredWeights(const BlockedCloud& cloud, const Eigen::VectorXd& weights) {
    std::vector<float> w(static_cast<size_t>(cloud.size()));
    for (size_t k = 0; k < w.size(); ++k) w[k] = static_cast<float>(weights[cloud.order()[k]]);
    return w;
}
}  // namespace

bool CpdEStep::UsesTruncation(double sigma2) const {
    switch (options_.mode) {
        case GaussSumMode::kDense:
            return false;
        case GaussSumMode::kTruncated:
            return true;
        case GaussSumMode::kAuto:
            break;
    }
    const Eigen::Index largest = std::max(source_.size(), target_blocked_.size());
    const double r = options_.truncation_sigmas * std::sqrt(sigma2);
    return largest >= options_.truncation_min_points &&
           r < options_.truncation_max_diag_fraction * target_blocked_.bbox_diagonal();
}

// Long on purpose: the fused pass (below) keeps den_n, p1 and PX of a chunk of targets in one
// loop nest so that nothing M x N is stored; split into functions, the chunk's accumulators
// and their fixed reduction order would have to travel between them.
void CpdEStep::ComputeFused(double sigma2, double c, CpdPosteriors& out) {
    const Eigen::Index n = target_blocked_.size();
    const Eigen::Index m = source_.size();
    // P_mn = K_mn / (den_n + c) normalises each target's column over all sources, so one
    // target's column, once computed, already gives its share of p1 and PX: one pass over the
    // targets, one exp per pair, nothing M x N stored. Targets go in fixed chunks, each with
    // its own float accumulators, reduced in chunk order: thread-count independent.
    constexpr Eigen::Index kTargetsPerChunk = 64;
    const Eigen::Index num_chunks = (n + kTargetsPerChunk - 1) / kTargetsPerChunk;
    partial_.resize(static_cast<size_t>(num_chunks * 4 * m));
    inv_den_.resize(static_cast<size_t>(n));
    out.pt1.resize(n);
    // Both clouds scaled by KernelRowScale: KernelRow's 2^-|q' - p'|^2 is then
    // exp(-|q - p|^2 / (2 sigma^2)) with no per-pair multiply for either constant (targets are
    // scaled as they are visited). Sources padded to KernelRow's multiple, far away (kernel 0).
    const float scale = KernelRowScale(sigma2);
    const Eigen::Index m_pad = (m + kKernelRowPad - 1) / kKernelRowPad * kKernelRowPad;
    scaled_source_.assign(static_cast<size_t>(3 * m_pad), kKernelRowFar);
    for (Eigen::Index i = 0; i < m; ++i) {
        scaled_source_[static_cast<size_t>(i)] = scale * source_.x()[i];
        scaled_source_[static_cast<size_t>(m_pad + i)] = scale * source_.y()[i];
        scaled_source_[static_cast<size_t>(2 * m_pad + i)] = scale * source_.z()[i];
    }
    const FloatPoints source_points{scaled_source_.data(), scaled_source_.data() + m_pad,
                                    scaled_source_.data() + 2 * m_pad, m_pad};
    const float* tx = target_blocked_.x();
    const float* ty = target_blocked_.y();
    const float* tz = target_blocked_.z();
    const auto& t_order = target_blocked_.order();
    const bool parallel = omp_get_max_threads() > 1 && num_chunks > 1 && m * n >= 200000;
#pragma omp parallel if (parallel)
    {
        // Four kernel columns (4 x 717 floats stay in L1), then one accumulation pass over
        // them (AxpyRows4: a quarter of the accumulator traffic, same bits as one by one).
        constexpr Eigen::Index kBlock = 4;
        std::vector<float> columns(static_cast<size_t>(kBlock * m_pad));
        std::array<std::array<float, 4>, kBlock> weights{};
#pragma omp for schedule(static)
        for (Eigen::Index chunk = 0; chunk < num_chunks; ++chunk) {
            float* acc = partial_.data() + chunk * 4 * m;
            std::fill(acc, acc + 4 * m, 0.0f);
            const std::array<float*, 4> accs{acc, acc + m, acc + 2 * m, acc + 3 * m};
            const Eigen::Index j1 = std::min(n, (chunk + 1) * kTargetsPerChunk);
            for (Eigen::Index j0 = chunk * kTargetsPerChunk; j0 < j1; j0 += kBlock) {
                const Eigen::Index block = std::min(kBlock, j1 - j0);
                for (Eigen::Index t = 0; t < block; ++t) {
                    const Eigen::Index j = j0 + t;
                    const double sum =
                        KernelRow(source_points, scale * Eigen::Vector3f(tx[j], ty[j], tz[j]),
                                  columns.data() + t * m_pad);
                    const double den = sum == 0.0 ? kDenFloor : sum;
                    const double inv = 1.0 / (den + c);
                    inv_den_[static_cast<size_t>(j)] = static_cast<float>(inv);
                    out.pt1[t_order[static_cast<size_t>(j)]] = den * inv;
                    const auto w = static_cast<float>(inv);
                    weights[static_cast<size_t>(t)] = {w, w * tx[j], w * ty[j], w * tz[j]};
                }
                if (block == kBlock) {
                    AxpyRows4(columns.data(), m_pad, m, weights, accs);
                } else {
                    for (Eigen::Index t = 0; t < block; ++t) {
                        AxpyRow(columns.data() + t * m_pad, m, weights[static_cast<size_t>(t)],
                                accs);
                    }
                }
            }
        }
    }
    // Chunks reduced in chunk order, in double: element-wise passes over the four m-long
    // accumulators (vectorisable, unlike a per-source loop over chunks; same additions).
    totals_.assign(static_cast<size_t>(4 * m), 0.0);
    for (Eigen::Index chunk = 0; chunk < num_chunks; ++chunk) {
        const float* acc = partial_.data() + chunk * 4 * m;
        for (Eigen::Index k = 0; k < 4 * m; ++k) totals_[static_cast<size_t>(k)] += acc[k];
    }
    out.p1.resize(m);
    out.px.resize(m, 3);
    const Eigen::RowVector3d origin = target_blocked_.origin().transpose();
    const auto& s_order = source_.order();
    for (Eigen::Index i = 0; i < m; ++i) {
        const double t0 = totals_[static_cast<size_t>(i)];
        const Eigen::Index row = s_order[static_cast<size_t>(i)];
        out.p1[row] = t0;
        out.px.row(row) = Eigen::RowVector3d(totals_[static_cast<size_t>(m + i)],
                                             totals_[static_cast<size_t>(2 * m + i)],
                                             totals_[static_cast<size_t>(3 * m + i)]) +
                          t0 * origin;
    }
    out.np = out.p1.sum();
    out.truncated = false;
    out.compressed_cells = 0;
    out.evaluated_pairs = m * n;
}

// Small dense problems go to ComputeFused; the rest is two kd-tree passes (den_n, then p1 and
// PX), each choosing between cell-compressed and exact sums. Kept in one function so both
// passes visibly share the cutoff, the cell size and the den floor.
void CpdEStep::Compute(const Transform& T, double sigma2, double c, CpdPosteriors& out) {
    if (!(c >= 0.0) || !std::isfinite(c)) {
        throw std::invalid_argument("CpdEStep: outlier constant c must be finite and >= 0");
    }
    const bool truncated = UsesTruncation(sigma2);
    const double cutoff = truncated ? options_.truncation_sigmas * std::sqrt(sigma2)
                                    : UnderflowRadiusSigmas() * std::sqrt(sigma2);
    source_.SetTransform(T);
    const Eigen::Index n = target_blocked_.size();
    const Eigen::Index m = source_.size();
    // Dense problems up to kFusedMaxEntries pairs: one fused pass, each exp computed once.
    if (!truncated && m * n <= kFusedMaxEntries) {
        ComputeFused(sigma2, c, out);
        return;
    }
    // Compression (auto mode at scale): cells of edge kappa * sigma in each summed-over cloud.
    const bool may_compress = options_.mode == GaussSumMode::kAuto &&
                              options_.cluster_cell_sigmas > 0.0 &&
                              std::max(m, n) >= options_.cluster_min_points;
    const double cell = options_.cluster_cell_sigmas * std::sqrt(sigma2);
    Eigen::Index cells_used = 0;
    bool compressed = false;

    // Pass 1: den_n = sum_m K_mn at every target point.
    if (may_compress) {
        // Cells in the source's own frame, edge cell / s, so they have edge `cell` once moved.
        const double s = T.topLeftCorner<3, 3>().col(0).norm();
        const CellCompressed cs = CompressToCells(source_points_, nullptr, cell / s);
        if (CompressionPays(cs.centroids.rows(), m)) {
            BlockedCloud cells(cs.centroids, target_blocked_.origin());
            cells.SetTransform(T);
            const std::vector<float> w = StoredWeights(cells, cs.weights);
            KernelSums(target_blocked_, cells, sigma2, cutoff, w.data(), false, pass1_);
            cells_used += cells.size();
            compressed = true;
        }
    }
    if (!compressed) {
        KernelSums(target_blocked_, source_, sigma2, cutoff, nullptr, false, pass1_);
        cells_used += m;
    }
    inv_den_.resize(static_cast<size_t>(n));
    out.pt1.resize(n);
    const auto& t_order = target_blocked_.order();
    for (Eigen::Index k = 0; k < n; ++k) {
        const double den = pass1_.m0[k] == 0.0 ? kDenFloor : pass1_.m0[k];
        const double inv = 1.0 / (den + c);
        inv_den_[static_cast<size_t>(k)] = static_cast<float>(inv);
        // sum_m K_mn / (den_n + c) = 1 - c / (den_n + c), as probreg (floored den).
        out.pt1[t_order[static_cast<size_t>(k)]] = den * inv;
    }

    // Pass 2: p1_m = sum_n K_mn / (den_n + c) and PX_m = sum_n K_mn x_n / (den_n + c).
    bool compressed2 = false;
    if (may_compress) {
        Eigen::VectorXd w_input(n);
        for (Eigen::Index k = 0; k < n; ++k) {
            w_input[t_order[static_cast<size_t>(k)]] = inv_den_[static_cast<size_t>(k)];
        }
        const CellCompressed ct = CompressToCells(target_points_, &w_input, cell);
        if (CompressionPays(ct.centroids.rows(), n)) {
            // Weighted centroids: sum_n w_n K(y, x_n) x_n ~ W_c K(y, xbar_c) xbar_c.
            BlockedCloud cells(ct.centroids, target_blocked_.origin());
            const std::vector<float> w = StoredWeights(cells, ct.weights);
            KernelSums(source_, cells, sigma2, cutoff, w.data(), true, pass2_);
            cells_used += cells.size();
            compressed2 = true;
        }
    }
    if (!compressed2) {
        KernelSums(source_, target_blocked_, sigma2, cutoff, inv_den_.data(), true, pass2_);
        cells_used += n;
    }
    out.p1.resize(m);
    out.px.resize(m, 3);
    const Eigen::RowVector3d origin = target_blocked_.origin().transpose();
    const auto& s_order = source_.order();
    for (Eigen::Index k = 0; k < m; ++k) {
        const Eigen::Index row = s_order[static_cast<size_t>(k)];
        out.p1[row] = pass2_.m0[k];
        out.px.row(row) = pass2_.m1.row(k) + pass2_.m0[k] * origin;  // back to absolute x_n
    }
    out.np = out.p1.sum();
    out.truncated = truncated;
    out.compressed_cells = (compressed || compressed2) ? cells_used : 0;
    out.evaluated_pairs = pass1_.evaluated_pairs + pass2_.evaluated_pairs;
}

namespace {

constexpr int kDim = 3;
/// probreg's floor for sigma^2 (np.finfo(np.float32).eps): keeps ln(sigma^2) and 1/sigma^2
/// finite once a clean pair has converged exactly.
constexpr double kSigma2Floor = 1.19e-7;

/// One M-step's outputs (docs/probabilistic-baselines.md, CPD M-step).
struct MStep {
    Transform T = Transform::Identity();
    double scale = 1.0;
    double sigma2 = 0.0;
    double q = 0.0;
};

/// CPD M-step on the original source Y (Myronenko & Song 2010, Fig. 2, rigid), with probreg's
/// sigma^2 variants.
MStep MaximizationStep(const PointCloud& Y, const PointCloud& X, const CpdPosteriors& post,
                       bool update_scale, bool probreg_sigma2) {
    const double np = post.np;
    const Eigen::Vector3d mu_x = post.px.colwise().sum().transpose() / np;
    const Eigen::Vector3d mu_y = (Y.transpose() * post.p1) / np;
    const PointCloud yc = Y.rowwise() - mu_y.transpose();
    // A = PX^T Yc - mu_x (p1^T Yc)
    const Eigen::Matrix3d A = post.px.transpose() * yc - mu_x * (post.p1.transpose() * yc);
    const double b = (yc.rowwise().squaredNorm().transpose() * post.p1).value();
    const ProcrustesResult fit = ProcrustesFromMoments(mu_y, mu_x, A, b, update_scale);
    if (!fit.valid) throw std::runtime_error("M-step produced a non-finite rotation");
    const double a = (A.transpose() * fit.R).trace();
    const double cx =
        ((X.rowwise() - mu_x.transpose()).rowwise().squaredNorm().transpose() * post.pt1).value();

    MStep out;
    out.scale = update_scale ? a / b : 1.0;
    out.T = MakeTransform(out.scale * fit.R, mu_x - out.scale * fit.R * mu_y);
    const double s = out.scale;
    double sigma2 = 0.0;
    if (probreg_sigma2) {
        // probreg: (cx - s a) with scale, (cx + b - a) without: the latter is its bug.
        sigma2 = update_scale ? (cx - s * a) / (np * kDim) : (cx + b - a) / (np * kDim);
    } else {
        sigma2 = (cx - 2.0 * s * a + s * s * b) / (np * kDim);  // maximum likelihood
    }
    out.sigma2 = std::max(sigma2, kSigma2Floor);
    out.q = (cx - 2.0 * s * a + s * s * b) / (2.0 * out.sigma2) +
            kDim * np * 0.5 * std::log(out.sigma2);
    return out;
}

constexpr char kCpdName[] = "cpd";

class CpdMethod final : public ParamMethod<CpdOptions> {
public:
    using ParamMethod::ParamMethod;

protected:
    bool AllowsScale() const override { return options().update_scale; }

    AlignResult DoAlign(const PointCloud& Y, const PointCloud& X,
                        const AlignContext& /*context*/) override {
        const double m = static_cast<double>(Y.rows());
        const double n = static_cast<double>(X.rows());
        GaussSumOptions gs;
        gs.mode = options().e_step;
        gs.truncation_sigmas = options().truncation_sigmas;
        gs.truncation_min_points = options().truncation_min_points;
        gs.cluster_cell_sigmas = options().cluster_cell_sigmas;
        gs.cluster_min_points = options().cluster_min_points;
        CpdEStep e_step(Y, X, gs);
        const bool probreg_sigma2 = options().sigma2_formula == CpdSigma2Formula::kProbreg;

        // Init: R = I, t = 0, s = 1, sigma^2 = sqsum, q0 = 1 + N D/2 ln sigma^2.
        MStep state;
        state.sigma2 = options().sigma2 > 0.0 ? options().sigma2 : SquaredDistanceMean(Y, X);
        state.sigma2 = std::max(state.sigma2, kSigma2Floor);
        state.q = 1.0 + n * kDim * 0.5 * std::log(state.sigma2);

        Convergence conv;
        conv.stop_reason = "max_iterations";
        CpdPosteriors post;
        int truncated_iterations = 0;
        int compressed_iterations = 0;
        std::int64_t evaluated_pairs = 0;
        for (int it = 1; it <= options().maxiter; ++it) {
            // c = (2 pi sigma^2)^(D/2) w/(1-w) M/N: the uniform outlier term (CPD eq. (7)).
            const double c = std::pow(2.0 * kPi * state.sigma2, 0.5 * kDim) * options().w /
                             (1.0 - options().w) * m / n;
            e_step.Compute(state.T, state.sigma2, c, post);
            truncated_iterations += post.truncated ? 1 : 0;
            compressed_iterations += post.compressed_cells > 0 ? 1 : 0;
            evaluated_pairs += post.evaluated_pairs;
            if (!(post.np > 0.0)) {
                conv.stop_reason = "no_correspondences";  // keep the previous transform
                break;
            }
            const MStep next = MaximizationStep(Y, X, post, options().update_scale, probreg_sigma2);
            const double dq = std::abs(next.q - state.q);
            state = next;
            conv.iterations = it;
            if (dq < options().tol) {
                conv.stop_reason = "converged";
                break;
            }
        }
        conv.objective = state.q;

        AlignResult r;
        r.T_target_source = state.T;
        r.iterations = conv.iterations;
        r.stop_reason = conv.stop_reason;
        r.scale = state.scale;
        r.extra = conv.ToJson();
        r.extra["sigma2"] = state.sigma2;
        r.extra["scale"] = state.scale;
        r.extra["truncated_iterations"] = truncated_iterations;
        r.extra["compressed_iterations"] = compressed_iterations;
        r.extra["kernel_evaluations"] = evaluated_pairs;
        return r;
    }
};

}  // namespace

CpdOptions ParseCpdOptions(const nlohmann::json& j) { return ParseParams<CpdOptions>(kCpdName, j); }

MethodInfo CpdMethodInfo() {
    MethodInfo info = MakeMethodInfo<CpdMethod, CpdOptions>(
        kCpdName,
        "rigid Coherent Point Drift (Myronenko & Song 2010) per probreg 0.3.7; fused float SIMD "
        "E-step (kd-leaf pruning, optional 4-sigma truncation), double M-step");
    info.paper_label = "CPD";  // the row of the OGMM paper's tables
    return info;
}

}  // namespace regbench
