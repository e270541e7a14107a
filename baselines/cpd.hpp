#pragma once
// Rigid Coherent Point Drift (Myronenko & Song, TPAMI 2010) as probreg 0.3.7 implements it,
// with its two deviations from the paper made explicit options (docs/probabilistic-baselines.md,
// "CPD").
#include <nlohmann/json.hpp>
#include <string>

#include "core/params.hpp"
#include "core/registration.hpp"
#include "gmm/gauss_sum.hpp"
#include "gmm/gmm_common.hpp"

namespace regbench {

/// How CPD updates sigma^2 after each M-step.
enum class CpdSigma2Formula {
    kMl,       ///< (cx - 2sa + s^2 b)/(Np D): the maximum-likelihood update
    kProbreg,  ///< (cx + b - a)/(Np D): probreg's formula (stalls without scale)
};
REGBENCH_CHOICES(CpdSigma2Formula,
                 {{CpdSigma2Formula::kMl, "ml"}, {CpdSigma2Formula::kProbreg, "probreg"}})

/// Options of `cpd`: the correct rigid CPD by default; compat "probreg" presets
/// update_scale = true and sigma2_formula = probreg (ApplyCompat); explicit values always win.
/// w, maxiter, tol and sigma2 are the GmmEmOptions base (gmm/gmm_common.hpp).
struct CpdOptions : GmmEmOptions {
    bool update_scale = false;  ///< estimate a scale s (similarity transform)
    CpdSigma2Formula sigma2_formula = CpdSigma2Formula::kMl;  ///< "ml" or "probreg"
    Compat compat = Compat::kNone;                            ///< "none" or "probreg"
    GaussSumMode e_step = GaussSumMode::kAuto;                ///< "auto", "dense" or "truncated"
    double truncation_sigmas = 4.0;                           ///< truncated E-step radius in sigmas
    /// auto: truncate only if max(M, N) >= this and r < 1/4 of the target bbox diagonal
    int truncation_min_points = 20000;
    /// auto, at scale: while a cloud has under half as many cells of edge cluster_cell_sigmas *
    /// sigma as points, each E-step pass sums over its cells' weighted centroids
    /// (docs/performance.md: accuracy cost)
    double cluster_cell_sigmas = 0.25;
    int cluster_min_points = 20000;  ///< auto: compress only if max(M, N) >= this

    template <class F>
    void Fields(F&& f) {
        f("w", w, "weight of the uniform outlier component; probreg default 0");
        f("maxiter", maxiter, "maximum EM iterations; probreg 50");
        f("tol", tol, "stop when |q - q_prev| < tol, absolute on the objective q; probreg 1e-3");
        f("update_scale", update_scale,
          "estimate a scale s (similarity transform); default false, true under compat=probreg");
        f("sigma2_formula", sigma2_formula,
          "\"ml\": (cx - 2sa + s^2 b)/(Np D); \"probreg\": (cx + b - a)/(Np D) without scale "
          "(probreg's bug, sigma^2 stalls); default ml, probreg under compat=probreg");
        f("sigma2", sigma2, "initial sigma^2; 0 = sqsum(Y, X) as probreg");
        f("compat", compat,
          "\"none\" (correct rigid CPD) or \"probreg\" (update_scale=true and probreg's sigma^2 "
          "formula unless those are given explicitly)");
        f("e_step", e_step,
          "\"auto\" (dense or cell-compressed, truncated once the switch rule holds), \"dense\" "
          "(exact up to float underflow) or \"truncated\" (always r = truncation_sigmas * sigma)");
        f("truncation_sigmas", truncation_sigmas,
          "truncated E-step radius in sigmas; 4 -> edge kernel 3.4e-4");
        f("truncation_min_points", truncation_min_points,
          "auto: truncate only if max(M, N) >= this and r < 1/4 of the target bbox diagonal");
        f("cluster_cell_sigmas", cluster_cell_sigmas,
          "auto, at scale: while a cloud has under half as many cells of edge cluster_cell_sigmas "
          "* sigma as points, each E-step pass sums over its cells' weighted centroids "
          "(docs/performance.md: accuracy cost); 0 = never");
        f("cluster_min_points", cluster_min_points, "auto: compress only if max(M, N) >= this");
    }
    void Validate(ParamCheck& c) const {
        GmmEmOptions::Validate(c);
        c.Above("truncation_sigmas", truncation_sigmas, 0.0);
        c.Finite("truncation_sigmas", truncation_sigmas);
        c.AtLeast("truncation_min_points", truncation_min_points, 0);
        c.AtLeast("cluster_cell_sigmas", cluster_cell_sigmas, 0.0);
        c.AtMost("cluster_cell_sigmas", cluster_cell_sigmas, 1.0);
        c.AtLeast("cluster_min_points", cluster_min_points, 0);
    }
    /// Scale guard class: the dense E-step is O(N * M); auto and truncated switch to their
    /// approximations (cell compression, truncation) at scale.
    CostClass Cost() const {
        return e_step == GaussSumMode::kDense ? CostClass::kQuadratic : CostClass::kNearLinear;
    }
    /// compat "probreg": probreg 0.3.7's defaults for these keys.
    void ApplyCompat() {
        if (compat != Compat::kProbreg) return;
        update_scale = true;
        sigma2_formula = CpdSigma2Formula::kProbreg;
    }
};

/// Sufficient statistics of one CPD E-step (Myronenko & Song 2010, eq. (7) and Fig. 2), in the
/// clouds' input order, all in double.
struct CpdPosteriors {
    Eigen::VectorXd p1;      ///< P 1 (M)
    Eigen::VectorXd pt1;     ///< P^T 1 (N)
    PointCloud px;           ///< P X (M x 3), in the target's input frame
    double np = 0.0;         ///< sum(p1)
    bool truncated = false;  ///< whether the truncated evaluation was used
    /// Cells the compressed evaluation summed over (source cells in pass 1 plus target cells
    /// in pass 2; a pass left exact counts its points); 0 when neither pass was compressed.
    Eigen::Index compressed_cells = 0;
    std::int64_t evaluated_pairs = 0;  ///< kernel evaluations in both passes
};

/// The CPD E-step, P_mn = K_mn / (den_n + c), K_mn = exp(-|T(y_m) - x_n|^2 / 2 sigma^2),
/// den_n = sum_m K_mn (0 becomes kDenFloor), in two passes and without storing P:
///   pass 1: den_n by kernel sums over the moved source at each target point;
///   pass 2: p1 and PX by kernel sums over the target, weighted by 1/(den_n + c), at each moved
///           source point; pt1_n = den_n / (den_n + c) follows without a second sum.
/// Dense problems up to kFusedMaxEntries pairs run as one fused pass instead: each target's
/// kernel column is normalised and accumulated into p1 and PX as soon as it is computed.
/// At scale (GaussSumOptions::cluster_*), the summed-over cloud of each pass is replaced by
/// its cell-compressed form (source cells of edge kappa sigma in pass 1, target cells weighted
/// by 1/(den_n + c) in pass 2) while sigma is large; queries stay the exact points, so p1, pt1
/// and PX keep one entry per point.
/// Holds prepared copies of both clouds, so build it once per registration and call Compute
/// every iteration. Not thread-safe (scratch buffers); Compute itself uses OpenMP.
class CpdEStep {
public:
    /// probreg's floor for an all-zero column: np.finfo(np.float32).eps.
    static constexpr double kDenFloor = 1.19e-7;
    /// Dense E-steps with M N up to this run fused (per-chunk accumulators: M N / 4 bytes).
    static constexpr Eigen::Index kFusedMaxEntries = Eigen::Index{1} << 22;

    CpdEStep(const PointCloud& source, const PointCloud& target, GaussSumOptions options = {});

    /// One E-step for the source moved by T (a similarity), variance sigma2 > 0 and outlier
    /// constant c = (2 pi sigma2)^(D/2) w/(1-w) M/N >= 0.
    void Compute(const Transform& T, double sigma2, double c, CpdPosteriors& out);

    /// True when Compute with this sigma2 would truncate (the options' switch rule).
    bool UsesTruncation(double sigma2) const;

private:
    /// Whether a pass summing over `points` compressed into `cells` cells should use them.
    bool CompressionPays(Eigen::Index cells, Eigen::Index points) const;
    /// The dense E-step in one fused pass over the targets (one exp per pair, nothing M x N
    /// stored); used while M N <= kFusedMaxEntries.
    void ComputeFused(double sigma2, double c, CpdPosteriors& out);

    GaussSumOptions options_;
    PointCloud source_points_, target_points_;  ///< input copies, for the compressed passes
    BlockedCloud source_;
    BlockedCloud target_blocked_;
    KernelSumResult pass1_, pass2_;
    std::vector<float> inv_den_;        ///< target stored order
    std::vector<float> partial_;        ///< fused path: float p1/PX accumulators per target chunk
    std::vector<float> scaled_source_;  ///< fused path: source x, y, z * KernelRowScale, padded
    std::vector<double> totals_;        ///< fused path: the chunks' sum, p1 then PX's x, y, z
};

/// Parses and validates CPD options, applying the compat preset to keys absent from `j`.
/// Throws std::invalid_argument naming the offending parameter.
CpdOptions ParseCpdOptions(const nlohmann::json& j);

/// `cpd`: rigid (optionally similarity) CPD, fused float E-step with exact double M-step.
MethodInfo CpdMethodInfo();

}  // namespace regbench
