#include "baselines/filterreg.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/kabsch.hpp"
#include "core/kd_tree.hpp"
#include "core/math_constants.hpp"
#include "core/normals.hpp"
#include "core/transform.hpp"
#include "gmm/gmm_common.hpp"
#include "gmm/permutohedral.hpp"

namespace regbench {
namespace {

constexpr char kName[] = "filterreg";
/// probreg's `alpha`: keep the blur only while the blurred lattice has <= 0.015 N vertices
/// (N = target points); otherwise rebuild without blur.
constexpr double kBlurVertexRatio = 0.015;
/// Exact estimator: Gaussians beyond 3 sigma weigh < exp(-4.5) ~ 1.1% of the peak and are cut.
constexpr double kExactCutoffSigmas = 3.0;
/// Exact estimator: use the kd-tree once the cutoff radius is below this fraction of the
/// target's bounding-box diagonal; above it nearly every pair is inside, so loop densely.
constexpr double kTreeRadiusFraction = 0.25;
constexpr std::int64_t kParallelMinPoints = 2048;

// ---------------------------------------------------------------------------------------------
// E-step

/// Column layout of the per-target values the filter carries: 1, x (3), then optionally
/// |x|^2 and the normal (3).
struct Channels {
    int m2 = -1;
    int nx = -1;
    int width = 4;
};

Channels MakeChannels(bool with_m2, bool with_normals) {
    Channels ch;
    if (with_m2) ch.m2 = ch.width++;
    if (with_normals) {
        ch.nx = ch.width;
        ch.width += 3;
    }
    return ch;
}

/// Computes the filtered target moments at moved source points. Keeps what depends only on
/// the target (and sigma) between calls: with sigma fixed (probreg's default) the no-blur
/// lattice over the target, its splatted values and the blur decision for the target alone
/// are built once.
class MomentEstimator {
public:
    MomentEstimator(const PointCloud& target, const Normals* normals, bool with_m2,
                    FilterRegEstimator estimator, LatticeBlur blur)
        : target_(target),
          normals_(normals),
          channels_(MakeChannels(with_m2, normals != nullptr)),
          estimator_(estimator),
          blur_(blur) {
        if (estimator_ == FilterRegEstimator::kExact) {
            tree_ = std::make_unique<KdTree>(target_);
            const Eigen::Vector3d extent =
                target_.colwise().maxCoeff() - target_.colwise().minCoeff();
            diagonal_ = extent.norm();
        } else {
            // Values as probreg passes them: float64 computed, then cast to float32.
            values_.resize(target_.rows(), channels_.width);
            for (Eigen::Index j = 0; j < target_.rows(); ++j) {
                values_(j, 0) = 1.0f;
                for (int k = 0; k < 3; ++k) values_(j, 1 + k) = static_cast<float>(target_(j, k));
                if (channels_.m2 >= 0) {
                    values_(j, channels_.m2) = static_cast<float>(target_.row(j).squaredNorm());
                }
                if (channels_.nx >= 0) {
                    for (int k = 0; k < 3; ++k) {
                        values_(j, channels_.nx + k) = static_cast<float>((*normals_)(j, k));
                    }
                }
            }
        }
    }

    FilterRegMoments Compute(const PointCloud& moved, double sigma2) {
        return estimator_ == FilterRegEstimator::kExact ? Exact(moved, sigma2)
                                                        : Lattice(moved, sigma2);
    }

private:
    static LatticeFeatures Features(const PointCloud& points, double sigma) {
        // probreg divides in float64, then the lattice takes float32.
        return (points / sigma).cast<float>();
    }

    void PrepareTarget(double sigma2, Eigen::Index num_source) {
        if (sigma2 == prepared_sigma2_ && num_source == prepared_sources_) return;
        prepared_sigma2_ = sigma2;
        prepared_sources_ = num_source;
        LatticeFeatures features = Features(target_, std::sqrt(sigma2));
        // The reference's padding simplex (at the zero feature) belongs in the blurred
        // lattice: it counts toward the size and relays values in the blur. It holds 0, so
        // the plain lattice does not need it.
        padded_ = PermutohedralLattice::ReferencePadding(target_.rows() + num_source) > 0;
        plain_.Build(features, false);
        plain_values_ = plain_.Splat(values_, 0, plain_.NumPoints());
        if (padded_) {
            features.conservativeResize(features.rows() + 1, Eigen::NoChange);
            features.row(features.rows() - 1).setZero();
        }
        // Adding the source points only adds vertices, so a target that alone exceeds the
        // limit rules the blur out for every iteration at this sigma (the build stops there).
        if (blur_ == LatticeBlur::kOff) {
            blur_possible_ = false;
        } else {
            const int limit = blur_ == LatticeBlur::kOn ? -1 : BlurLimit();
            blur_possible_ = blurred_target_.Build(features, true, limit);
        }
    }

    /// Largest vertex count that keeps the blur: probreg blurs unless size > 0.015 N.
    int BlurLimit() const {
        return static_cast<int>(std::floor(kBlurVertexRatio * static_cast<double>(target_.rows())));
    }

    FilterRegMoments Lattice(const PointCloud& moved, double sigma2) {
        PrepareTarget(sigma2, moved.rows());
        const LatticeFeatures source_features = Features(moved, std::sqrt(sigma2));
        FilterRegMoments out;
        LatticeValues sliced;
        const bool try_blur =
            blur_ == LatticeBlur::kOn || (blur_ == LatticeBlur::kAuto && blur_possible_);
        if (try_blur) {
            // The lattice over [X; Y] (probreg stacks [Y; X]; the order changes vertex ids only).
            PermutohedralLattice lattice = blurred_target_;
            const bool within =
                lattice.AddPoints(source_features, blur_ == LatticeBlur::kOn ? -1 : BlurLimit());
            if (within) {
                out.lattice_vertices = lattice.NumVertices();
                LatticeValues vertex_values =
                    lattice.Splat(values_, 0, static_cast<int>(target_.rows()));
                lattice.Blur(vertex_values);
                // Points: targets, the padding point (if any), then the sources.
                const int first = static_cast<int>(target_.rows()) + (padded_ ? 1 : 0);
                lattice.Slice(vertex_values, first, first + static_cast<int>(moved.rows()), sliced);
                out.blurred = true;
            }
        }
        if (!out.blurred) {
            // Without blur, source-only vertices hold 0 and pass nothing on: slicing the
            // target's lattice at the source features gives probreg's result.
            plain_.SliceAt(source_features, plain_values_, sliced);
        }
        LatticeValuesToMoments(sliced, out);
        return out;
    }

    void LatticeValuesToMoments(const LatticeValues& sliced, FilterRegMoments& out) const {
        out.m0 = sliced.col(0).cast<double>();
        out.m1 = sliced.middleCols(1, 3).cast<double>();
        if (channels_.m2 >= 0) out.m2 = sliced.col(channels_.m2).cast<double>();
        if (channels_.nx >= 0) out.nx = sliced.middleCols(channels_.nx, 3).cast<double>();
    }

    FilterRegMoments Exact(const PointCloud& moved, double sigma2) {
        const Eigen::Index m = moved.rows();
        const double radius = kExactCutoffSigmas * std::sqrt(sigma2);
        const double radius2 = radius * radius;
        const double inv_2s2 = 1.0 / (2.0 * sigma2);
        const bool use_tree = radius < kTreeRadiusFraction * diagonal_;
        FilterRegMoments out;
        out.m0 = Eigen::VectorXd::Zero(m);
        out.m1 = PointCloud::Zero(m, 3);
        if (channels_.m2 >= 0) out.m2 = Eigen::VectorXd::Zero(m);
        if (channels_.nx >= 0) out.nx = PointCloud::Zero(m, 3);
#pragma omp parallel if (m >= kParallelMinPoints)
        {
            std::vector<std::pair<Eigen::Index, double>> hits;
#pragma omp for schedule(static)
            for (Eigen::Index i = 0; i < m; ++i) {
                const Eigen::Vector3d y = moved.row(i).transpose();
                hits.clear();
                if (use_tree) {
                    tree_->Radius(y, radius, hits);
                    // Sum in target order, as the dense loop does: identical sums either way.
                    std::sort(hits.begin(), hits.end());
                } else {
                    for (Eigen::Index j = 0; j < target_.rows(); ++j) {
                        const double d2 = (target_.row(j).transpose() - y).squaredNorm();
                        if (d2 <= radius2) hits.emplace_back(j, d2);
                    }
                }
                double m0 = 0.0;
                double m2 = 0.0;
                Eigen::Vector3d m1 = Eigen::Vector3d::Zero();
                Eigen::Vector3d nx = Eigen::Vector3d::Zero();
                for (const auto& [j, d2] : hits) {
                    if (d2 > radius2) continue;
                    const double k = std::exp(-d2 * inv_2s2);
                    const Eigen::Vector3d x = target_.row(j).transpose();
                    m0 += k;
                    m1 += k * x;
                    m2 += k * x.squaredNorm();
                    if (channels_.nx >= 0) nx += k * normals_->row(j).transpose();
                }
                out.m0[i] = m0;
                out.m1.row(i) = m1.transpose();
                if (channels_.m2 >= 0) out.m2[i] = m2;
                if (channels_.nx >= 0) out.nx.row(i) = nx.transpose();
            }
        }
        return out;
    }

    const PointCloud& target_;
    const Normals* normals_;
    Channels channels_;
    FilterRegEstimator estimator_;
    LatticeBlur blur_;
    // lattice
    LatticeValues values_;
    double prepared_sigma2_ = -1.0;
    Eigen::Index prepared_sources_ = -1;
    bool padded_ = false;
    PermutohedralLattice plain_;
    LatticeValues plain_values_;
    PermutohedralLattice blurred_target_;
    bool blur_possible_ = false;
    // exact
    std::unique_ptr<KdTree> tree_;
    double diagonal_ = 0.0;
};

// ---------------------------------------------------------------------------------------------
// M-step

struct MStep {
    bool ok = false;
    std::string failure;  ///< stop reason when !ok
    Eigen::Matrix3d dR = Eigen::Matrix3d::Identity();
    Eigen::Vector3d dt = Eigen::Vector3d::Zero();
    double q = 0.0;       ///< probreg's objective at the pre-update positions
    double sigma2 = 0.0;  ///< updated variance (the input one when not updating)
    Eigen::Index used = 0;
};

/// The points the M-step keeps (m0 > 0: some target mass reached them) and their weights.
struct Selection {
    std::vector<Eigen::Index> index;
    Eigen::VectorXd omega;  ///< m0 / (m0 + c)
    Eigen::VectorXd w;      ///< sqrt(omega / sigma2): probreg's drxdx
    PointCloud y;           ///< moved source points
    PointCloud u;           ///< m1 / m0
};

Selection Select(const PointCloud& moved, const FilterRegMoments& mom, double sigma2, double c) {
    Selection s;
    for (Eigen::Index i = 0; i < moved.rows(); ++i) {
        // probreg keeps m0 != 0; float rounding can leave a barycentric weight a hair below 0,
        // where probreg's sqrt would give NaN, so we keep m0 > 0.
        if (mom.m0[i] > 0.0) s.index.push_back(i);
    }
    const Eigen::Index n = static_cast<Eigen::Index>(s.index.size());
    s.omega.resize(n);
    s.w.resize(n);
    s.y.resize(n, 3);
    s.u.resize(n, 3);
    for (Eigen::Index k = 0; k < n; ++k) {
        const Eigen::Index i = s.index[static_cast<std::size_t>(k)];
        const double m0 = mom.m0[i];
        s.omega[k] = m0 / (m0 + c);
        s.w[k] = std::sqrt(s.omega[k] / sigma2);
        s.y.row(k) = moved.row(i);
        s.u.row(k) = mom.m1.row(i) / m0;
    }
    return s;
}

/// Variance update (FilterReg / probreg):
/// sigma2 = sum_i (m0_i |y_i|^2 - 2 y_i . m1_i + m2_i) / (m0_i + c) / (3 sum_i omega_i).
double UpdatedSigma2(const Selection& s, const FilterRegMoments& mom, double c) {
    double num = 0.0;
    for (Eigen::Index k = 0; k < s.y.rows(); ++k) {
        const Eigen::Index i = s.index[static_cast<std::size_t>(k)];
        const Eigen::Vector3d y = s.y.row(k).transpose();
        const double m0 = mom.m0[i];
        num +=
            (m0 * y.squaredNorm() - 2.0 * y.dot(mom.m1.row(i).transpose()) + mom.m2[i]) / (m0 + c);
    }
    return num / (3.0 * s.omega.sum());
}

/// pt2pt: Kabsch from y to u. probreg weights the centroids by w_i but H by w_i^2
/// (`kabsch.cc`); the consistent weighted least squares uses w_i^2 for both.
MStep PointToPoint(const Selection& s, bool probreg_weights) {
    MStep out;
    const Eigen::VectorXd w2 = s.w.array().square();
    const Eigen::VectorXd& wc = probreg_weights ? s.w : w2;
    const Eigen::Vector3d mu_y = (s.y.transpose() * wc) / wc.sum();
    const Eigen::Vector3d mu_u = (s.u.transpose() * wc) / wc.sum();
    const PointCloud yc = s.y.rowwise() - mu_y.transpose();
    const PointCloud uc = s.u.rowwise() - mu_u.transpose();
    const Eigen::Matrix3d H_u_y = uc.transpose() * w2.asDiagonal() * yc;
    const ProcrustesResult fit = ProcrustesFromMoments(mu_y, mu_u, H_u_y, 0.0, false);
    if (!fit.valid) {
        out.failure = "degenerate";
        return out;
    }
    out.ok = true;
    out.dR = fit.R;
    out.dt = fit.t;
    // q = sum_i w_i |y_i - u_i|: a sum of norms, as probreg.
    out.q = (s.w.array() * (s.y - s.u).rowwise().norm().array()).sum();
    return out;
}

/// pt2pl (FilterReg eq. (11)-(13), probreg `point_to_plane.cc`): Gauss-Newton on the twist
/// xi = (omega, tau) for residuals r_i = n_i . (u_i - y_i), Jacobian J_i = (y_i x n_i, n_i),
/// with n_i = nx_i / m0_i the filtered (unnormalised) normal. probreg weights J J^T and r J by
/// w_i; the consistent Gauss-Newton step for sum_i w_i^2 r_i^2 weights them by w_i^2.
MStep PointToPlane(const Selection& s, const FilterRegMoments& mom, bool probreg_weights) {
    using Matrix6d = Eigen::Matrix<double, 6, 6>;
    using Vector6d = Eigen::Matrix<double, 6, 1>;
    Matrix6d ata = Matrix6d::Zero();
    Vector6d atb = Vector6d::Zero();
    double r_sum = 0.0;
    for (Eigen::Index k = 0; k < s.y.rows(); ++k) {
        const Eigen::Index i = s.index[static_cast<std::size_t>(k)];
        const Eigen::Vector3d y = s.y.row(k).transpose();
        const Eigen::Vector3d u = s.u.row(k).transpose();
        const Eigen::Vector3d n = mom.nx.row(i).transpose() / mom.m0[i];
        const double r = n.dot(u - y);
        Vector6d jac;
        jac << y.cross(n), n;
        const double weight = probreg_weights ? s.w[k] : s.w[k] * s.w[k];
        ata.noalias() += weight * jac * jac.transpose();
        atb.noalias() += weight * r * jac;
        r_sum += s.w[k] * s.w[k] * r * r;
    }
    MStep out;
    const Vector6d xi = ata.ldlt().solve(atb);
    if (!xi.allFinite()) {
        out.failure = "degenerate";
        return out;
    }
    out.ok = true;
    const Eigen::Vector3d omega = xi.head<3>();
    const double angle = omega.norm();
    out.dR = angle > 0.0 ? RotationFromAxisAngle(omega, angle) : Eigen::Matrix3d::Identity();
    out.dt = xi.tail<3>();
    out.q = r_sum;
    return out;
}

// ---------------------------------------------------------------------------------------------
// The method

AlignResult AlignFilterReg(const FilterRegOptions& o, const PointCloud& source,
                           const PointCloud& target, const AlignContext& /*context*/) {
    const bool pt2pl = o.objective == FilterRegObjective::kPt2Pl;
    const bool probreg_weights = o.compat == Compat::kProbreg;
    Normals normals;
    if (pt2pl) normals = EstimateNormals(target, o.normals_k);
    MomentEstimator estimator(target, pt2pl ? &normals : nullptr, o.update_sigma2, o.estimator,
                              LatticeBlur::kAuto);

    const double m = static_cast<double>(source.rows());
    const double n = static_cast<double>(target.rows());
    double sigma2 =
        o.sigma2 > 0.0 ? o.sigma2 : std::max(SquaredDistanceMean(source, target), o.min_sigma2);
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    Eigen::Vector3d t = Eigen::Vector3d::Zero();

    Convergence conv;
    conv.stop_reason = "max_iterations";
    conv.objective = std::numeric_limits<double>::quiet_NaN();
    bool have_q = false;
    int blurred_iterations = 0;
    Eigen::Index used = 0;
    for (int it = 0; it < o.maxiter; ++it) {
        const PointCloud moved = (source * R.transpose()).rowwise() + t.transpose();
        const FilterRegMoments mom = estimator.Compute(moved, sigma2);
        // Outlier term c = w/(1-w) N/M (2 pi sigma2)^(D/2).
        const double c = o.w / (1.0 - o.w) * n / m * std::pow(2.0 * kPi * sigma2, 1.5);
        const Selection sel = Select(moved, mom, sigma2, c);
        if (sel.index.empty()) {
            conv.stop_reason = "no_overlap";  // probreg: stop and keep the previous transform
            break;
        }
        MStep step =
            pt2pl ? PointToPlane(sel, mom, probreg_weights) : PointToPoint(sel, probreg_weights);
        if (!step.ok) {
            conv.stop_reason = step.failure;
            break;
        }
        // R <- dR R, t <- dR t + dt.
        R = step.dR * R;
        t = step.dR * t + step.dt;
        if (o.update_sigma2) sigma2 = UpdatedSigma2(sel, mom, c);
        sigma2 = std::max(sigma2, o.min_sigma2);
        conv.iterations = it + 1;
        blurred_iterations += mom.blurred ? 1 : 0;
        used = static_cast<Eigen::Index>(sel.index.size());
        const bool converged = have_q && std::abs(step.q - conv.objective) < o.tol;
        conv.objective = step.q;
        have_q = true;
        if (converged) {
            conv.stop_reason = "converged";
            break;
        }
    }

    AlignResult result;
    result.T_target_source = MakeTransform(R, t);
    result.iterations = conv.iterations;
    result.stop_reason = conv.stop_reason;
    result.extra = conv.ToJson();
    result.extra["sigma2"] = sigma2;
    result.extra["blurred_iterations"] = blurred_iterations;
    result.extra["points_used"] = used;
    return result;
}

}  // namespace

FilterRegMoments FilterRegEStep(const PointCloud& moved_source, const PointCloud& target,
                                const Normals* target_normals, double sigma2, bool with_m2,
                                FilterRegEstimator estimator, LatticeBlur blur) {
    if (!(sigma2 > 0.0) || !std::isfinite(sigma2)) {
        throw std::invalid_argument("FilterRegEStep: sigma2 must be positive and finite");
    }
    if (target_normals != nullptr && target_normals->rows() != target.rows()) {
        throw std::invalid_argument("FilterRegEStep: target_normals must have one row per point");
    }
    MomentEstimator est(target, target_normals, with_m2, estimator, blur);
    return est.Compute(moved_source, sigma2);
}

namespace {

constexpr char kFilterRegName[] = "filterreg";

}  // namespace

FilterRegOptions ParseFilterRegOptions(const nlohmann::json& params) {
    return ParseParams<FilterRegOptions>(kFilterRegName, params);  // sigma2: null = "auto"
}

MethodInfo FilterRegMethodInfo() {
    MethodInfo info = MakeMethodInfo<FilterRegOptions>(
        kFilterRegName,
        "FilterReg (Gao & Tedrake 2019) as probreg's registration_filterreg: permutohedral-lattice "
        "E-step, weighted Kabsch (pt2pt) or twist (pt2pl) M-step; regbench C++",
        AlignFilterReg);
    info.paper_label = "FilterReg";  // the row of the OGMM paper's tables
    return info;
}

}  // namespace regbench
