#pragma once
// Rigid L2 distance between two Gaussian mixtures with a shared isotropic bandwidth, as
// probreg's RigidCostFunction / compute_l2_dist evaluate it (GMMReg, SVR). Dense exact sums:
// probreg's IFGT (eps 1e-4, random clustering) is replaced by the exact Gauss transform.
// Notation (probabilistic-baselines.md Sec. 2): theta = (q_w, q_x, q_y, q_z, t), q unnormalised.
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/enum_names.hpp"
#include "core/params.hpp"
#include "core/point_cloud.hpp"
#include "core/registration.hpp"
#include "gmm/bfgs.hpp"

namespace regbench {

/// Which gradient the cost returns.
enum class L2Gradient {
    kProbregHalf,  ///< probreg's g_i = ... / (2 sigma^2): exactly 1/2 of the true gradient
    kExact,        ///< the true gradient of f
};
REGBENCH_CHOICES(L2Gradient,
                 {{L2Gradient::kProbregHalf, "probreg_half"}, {L2Gradient::kExact, "exact"}})

/// Component means and (unnormalised) weights of one mixture.
struct MixtureFeatures {
    PointCloud means;
    Eigen::VectorXd weights;
};

/// R(q / |q|) for a quaternion in (w, x, y, z) order (transforms3d's quat2mat).
Eigen::Matrix3d RotationFromQuaternionWxyz(const Eigen::Vector4d& q);
/// dR(q/|q|)/dq_k, k = 0..3 (w, x, y, z): the exact derivative of the normalised quat2mat.
/// (probreg's se3_op.diff_rot_from_quaternion divides the off-diagonal correction by |q|^4
/// instead of |q|^2, which agrees only at |q| = 1; we use the exact form.)
std::array<Eigen::Matrix3d, 4> RotationDerivativeFromQuaternionWxyz(const Eigen::Vector4d& q);
/// T(theta) = [R(q/|q|), t] for theta = (q_w, q_x, q_y, q_z, t_x, t_y, t_z).
Transform TransformFromTheta(const Eigen::VectorXd& theta);

class KdTree;

/// How the L2 cost's Gaussian sums are evaluated at scale (docs/performance.md). Below
/// `min_pairs` = K_s * K_t everything is dense and exact; at or above it:
///  - both mixtures are cell-compressed (gmm/cell_compress.hpp) with cell edge
///    `compress_cell_sigmas` * sigma: the cost becomes the exact L2 of the compressed mixtures,
///    so its gradient stays consistent for BFGS;
///  - pairs farther apart than r = sigma sqrt(2 ln(1 / cutoff_tolerance)) are skipped, found by
///    a kd-tree radius search on the target components (gmmreg's own cutoff). Every skipped
///    term is below cutoff_tolerance times its weight product, so
///    |f_cutoff - f_dense| <= cutoff_tolerance * sum_ij phi_i phi_j / Z.
/// The `kernel_sums` option of GMMReg and SVR.
enum class L2KernelSums {
    kAuto,   ///< approximate from L2SumOptions::min_pairs on
    kDense,  ///< always dense and exact
};
REGBENCH_CHOICES(L2KernelSums, {{L2KernelSums::kAuto, "auto"}, {L2KernelSums::kDense, "dense"}})

struct L2SumOptions {
    L2KernelSums kernel_sums = L2KernelSums::kAuto;  ///< kDense: always dense and exact
    double min_pairs = 1e8;                          ///< K_s * K_t at which approximation starts
    double cutoff_tolerance = 1e-4;                  ///< relative kernel value at the cutoff radius
    double compress_cell_sigmas = 0.1;               ///< cell edge in sigmas; 0 = no compression

    /// Binds these fields under the JSON keys of GMMReg and SVR (core/params.hpp):
    /// kernel_sums and approx_min_pairs with the method's docs (its mixtures count the pairs),
    /// the cutoff and the compression with the meaning they have in both.
    template <class F>
    void Fields(F&& f, const char* kernel_sums_doc, const char* approx_min_pairs_doc) {
        f("kernel_sums", kernel_sums, kernel_sums_doc);
        f("approx_min_pairs", min_pairs, approx_min_pairs_doc);
        f("cutoff_tolerance", cutoff_tolerance,
          "kernel value at the cutoff radius; 1e-4 -> 4.29 sigma");
        f("compress_cell_sigmas", compress_cell_sigmas,
          "cell edge of the compression in sigmas; 0 = none");
    }
};

/// Cutoff radius, in sigmas, at which exp(-r^2 / 2) = tolerance: sqrt(2 ln(1 / tolerance)).
double CutoffRadiusSigmas(double tolerance);

/// f(theta) = -sum_ij phi_s_i phi_t_j / Z exp(-|R mu_s_i + t - mu_t_j|^2 / 2 sigma^2),
/// Z = (2 pi sigma^2)^(D/2), and its gradient w.r.t. theta (7 entries).
/// Sums are dense (O(K_s K_t) exps per call), parallel over source components with OpenMP
/// (thread-count independent: each row is summed alone, rows are reduced in order).
class RigidGmmL2Cost {
public:
    /// `cutoff_radius` (input units; infinity = dense): pairs farther apart are skipped.
    RigidGmmL2Cost(const MixtureFeatures& source, const MixtureFeatures& target, double sigma,
                   L2Gradient gradient,
                   double cutoff_radius = std::numeric_limits<double>::infinity());
    ~RigidGmmL2Cost();
    RigidGmmL2Cost(const RigidGmmL2Cost&) = delete;  // the kd-tree references target_means_
    RigidGmmL2Cost& operator=(const RigidGmmL2Cost&) = delete;
    /// Returns f(theta) and writes the gradient (probreg's half or exact) into grad.
    double operator()(const Eigen::VectorXd& theta, Eigen::VectorXd& grad) const;
    /// theta0 = (1, 0, 0, 0, 0, 0, 0): probreg's RigidCostFunction.initial().
    static Eigen::VectorXd InitialTheta();

private:
    PointCloud source_means_;
    Eigen::VectorXd source_weights_;
    // Target in structure-of-arrays form, weights pre-divided by Z.
    Eigen::VectorXd tx_, ty_, tz_, tw_;
    double sigma_;
    L2Gradient gradient_;
    double cutoff_radius_;
    PointCloud target_means_;       ///< referenced by tree_
    std::unique_ptr<KdTree> tree_;  ///< only with a finite cutoff
};

/// Where an L2 method optimises: y' = (y - c_source) / scale, x' = (x - c_target) / scale.
/// probreg works in the input frame (centers 0, scale 1); the "correct" modes centre both
/// clouds and divide by the source's sigma so that gtol and the rotation/translation coupling
/// do not depend on the input's units and offset.
struct L2Frame {
    Eigen::Vector3d source_center = Eigen::Vector3d::Zero();
    Eigen::Vector3d target_center = Eigen::Vector3d::Zero();
    double scale = 1.0;

    /// Centroids of each cloud, common scale `scale` (> 0).
    static L2Frame CenteredScaled(const PointCloud& source, const PointCloud& target, double scale);
    PointCloud SourceIn(const PointCloud& source) const;
    PointCloud TargetIn(const PointCloud& target) const;
    /// T_target_source in the input frame from T' estimated in this frame.
    Transform ToInput(const Transform& T_frame) const;
};

/// What the approximated L2 sums do for one (mixtures, sigma): each part only where it pays.
struct L2SumsPlan {
    MixtureFeatures source;  ///< compressed, or the input mixture
    MixtureFeatures target;  ///< compressed, or the input mixture
    bool compressed_source = false;
    bool compressed_target = false;
    double cutoff_radius = std::numeric_limits<double>::infinity();  ///< infinity = dense

    bool approximated() const {
        return compressed_source || compressed_target || std::isfinite(cutoff_radius);
    }
};

/// Decides the approximation for K_s K_t >= sums.min_pairs (otherwise: the inputs, dense):
///  - a mixture is cell-compressed only when that at least halves its components (a cloud
///    whose extent is large against sigma barely merges, and its compressed sums would cost
///    as much as the dense ones while adding error);
///  - the kd-tree cutoff is used only when its radius is below a quarter of the target's
///    bounding-box diagonal (otherwise nearly every pair is inside it and the radius search
///    costs more per pair than the dense SIMD row).
/// Either part alone keeps its stated accuracy bound; with neither the sums are exact.
L2SumsPlan PlanL2Sums(const MixtureFeatures& source, const MixtureFeatures& target, double sigma,
                      const L2SumOptions& sums);

/// One BFGS run of RigidGmmL2Cost from theta0 (probreg's minimize(..., method='BFGS')).
/// With `sums` approximating (K_s K_t >= sums.min_pairs), PlanL2Sums decides compression and
/// cutoff; `approximated` (optional) reports whether either was used.
BfgsResult MinimizeRigidL2(const MixtureFeatures& source, const MixtureFeatures& target,
                           double sigma, L2Gradient gradient, const Eigen::VectorXd& theta0,
                           const BfgsOptions& options, const L2SumOptions& sums = {},
                           bool* approximated = nullptr);

/// The mixture with components merged per cell of edge `cell` (weights summed, means the
/// weight-averaged centroids): the L2 cost of compressed mixtures approximates the original
/// to O((cell / sigma)^2).
MixtureFeatures CompressMixture(const MixtureFeatures& mixture, double cell);

/// The annealed L2 registration GMMReg and SVR share (probreg's
/// L2DistRegistration.registration): BFGS at bandwidth sigma, then sigma *= delta, until
/// outer_iterations steps or |f_k - f_{k-1}| < outer_tol (checked from the second step on).
/// Both methods' options structs derive from it and bind its fields under the same JSON keys
/// (gradient, delta, outer_iterations, outer_tol, maxiter, gtol, kernel_sums,
/// approx_min_pairs, cutoff_tolerance, compress_cell_sigmas) with their own docs.
struct AnnealedL2Options {
    L2Gradient gradient = L2Gradient::kExact;  ///< "probreg_half" (probreg's) or "exact"
    double delta = 0.9;                        ///< sigma *= delta per outer step
    int outer_iterations = 1;                  ///< outer (annealing) steps
    double outer_tol = 0.001;                  ///< stop the schedule when |f - f_prev| < outer_tol
    BfgsOptions bfgs = {200, 1e-6};            ///< every inner BFGS run (keys maxiter, gtol)
    L2SumOptions sums;  ///< dense or approximated Gaussian sums in every inner run

    /// The ranges of these fields, under the methods' JSON keys (core/params.hpp).
    void Validate(ParamCheck& c) const {
        c.Above("delta", delta, 0.0);
        c.AtMost("delta", delta, 1.0);
        c.AtLeast("outer_iterations", outer_iterations, 1);
        c.AtLeast("outer_tol", outer_tol, 0.0);
        c.AtLeast("maxiter", bfgs.maxiter, 0);
        c.AtLeast("gtol", bfgs.gtol, 0.0);
        c.AtLeast("approx_min_pairs", sums.min_pairs, 0.0);
        c.Above("cutoff_tolerance", sums.cutoff_tolerance, 0.0);
        c.Below("cutoff_tolerance", sums.cutoff_tolerance, 1.0);
        c.AtLeast("compress_cell_sigmas", sums.compress_cell_sigmas, 0.0);
        c.AtMost("compress_cell_sigmas", sums.compress_cell_sigmas, 1.0);
    }
    /// Scale guard class: the dense kernel sums are O(N * M); the approximations (the default)
    /// switch on by themselves above their size thresholds.
    CostClass Cost() const {
        return sums.kernel_sums == L2KernelSums::kDense ? CostClass::kQuadratic
                                                        : CostClass::kNearLinear;
    }
};

/// Outcome of MinimizeAnnealedL2.
struct AnnealedL2Result {
    Eigen::VectorXd theta;      ///< final (q, t), see TransformFromTheta
    BfgsResult last;            ///< the last inner BFGS run
    int iterations = 0;         ///< BFGS iterations summed over all outer steps
    int outer_steps = 0;        ///< outer steps run
    bool approximated = false;  ///< whether any inner run used approximated sums
};

/// Called at the start of every outer step with that step's bandwidth; refits the mixtures
/// in place (SVR refits its support vectors each step; GMMReg's mixtures stay fixed).
using RefitMixtures =
    std::function<void(double sigma, MixtureFeatures& source, MixtureFeatures& target)>;

/// The annealed L2 loop from theta = InitialTheta(). `refit` may be empty (fixed mixtures).
AnnealedL2Result MinimizeAnnealedL2(MixtureFeatures& source, MixtureFeatures& target, double sigma,
                                    const AnnealedL2Options& options,
                                    const RefitMixtures& refit = {});

/// The AlignResult of an annealed L2 fit made in `frame`: transform back in the input frame,
/// iterations, stop reason and the diagnostics both methods report (iterations, objective,
/// stop_reason, outer_iterations, evaluations).
AlignResult AnnealedL2AlignResult(const L2Frame& frame, const AnnealedL2Result& fit);

}  // namespace regbench
