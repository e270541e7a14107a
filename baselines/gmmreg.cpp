// GMMReg (Jian & Vemuri 2011) as probreg v0.3.7 runs it (probabilistic-baselines.md Sec. 2):
// fit a spherical GMM with K = min(800, floor(0.8 M)) components to each cloud, keep means and
// weights, minimise the rigid L2 cost f(theta) (Sec. 2 "Cost") with BFGS from the identity.
#include "baselines/gmmreg.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/params.hpp"
#include "core/rng.hpp"
#include "gmm/bfgs.hpp"
#include "gmm/gmm_common.hpp"
#include "gmm/gmm_fit.hpp"
#include "gmm/gmm_l2.hpp"

namespace regbench {
namespace {

constexpr char kName[] = "gmmreg";
/// probreg: n_gmm_components = min(n_gmm_components, int(0.8 M)).
constexpr double kComponentFraction = 0.8;

/// Where the mixtures come from.
enum class GmmFeatures {
    kSklearn,  ///< sklearn-style spherical GMM fit (probreg)
    kPoints,   ///< every point a component (Jian & Vemuri)
};
REGBENCH_CHOICES(GmmFeatures,
                 {{GmmFeatures::kSklearn, "sklearn"}, {GmmFeatures::kPoints, "points"}})

/// Options of `gmmreg`; the annealing, BFGS and kernel-sum fields are the shared
/// AnnealedL2Options base (gmm/gmm_l2.hpp), bound here with gmmreg's docs.
struct GmmRegOptions : AnnealedL2Options {
    Compat compat = Compat::kNone;           ///< "none" or "probreg"
    GmmFeatures gmm = GmmFeatures::kPoints;  ///< "sklearn" or "points"
    int n_gmm_components = 800;              ///< GMM components
    /// optimise with both clouds centred and divided by sigma (unit-free gtol)
    bool normalize = true;
    /// kernel bandwidth [input units], used only if use_estimated_sigma is false
    double sigma = 1.0;
    bool use_estimated_sigma = true;  ///< sigma = det(cov(source))^(1/6) (probreg default true)
    int gmm_max_iter = 100;           ///< EM iterations of each GMM fit (sklearn 100)
    /// EM stops when the mean log-likelihood changes by < gmm_tol (sklearn 1e-3)
    double gmm_tol = 0.001;
    int seed = 0;  ///< seed of the k-means++ initialisation (sklearn's is unseeded in probreg)

    template <class F>
    void Fields(F&& f) {
        f("compat", compat,
          "\"none\" (default, the correct algorithm: defaults become gmm=points, gradient=exact, "
          "normalize=true, gtol=1e-6, maxiter=200) or \"probreg\" (probreg v0.3.7 behaviour); "
          "explicit keys win");
        f("gmm", gmm,
          "features: \"sklearn\" = GaussianMixture(K, spherical) means/weights (probreg), "
          "\"points\" = every point with weight 1/N (Jian & Vemuri, faster)");
        f("n_gmm_components", n_gmm_components,
          "GMM components; K = min(this, floor(0.8 M)) from the source size M");
        f("gradient", gradient,
          "\"probreg_half\" = probreg's gradient (exactly 1/2 of the true one), \"exact\"");
        f("normalize", normalize,
          "optimise with both clouds centred and divided by sigma (unit-free gtol); probreg: "
          "false");
        f("sigma", sigma,
          "kernel bandwidth [input units], used only if use_estimated_sigma is false");
        f("use_estimated_sigma", use_estimated_sigma,
          "sigma = det(cov(source))^(1/6) (probreg default true)");
        f("delta", delta, "sigma *= delta after each outer iteration (probreg 0.9)");
        f("outer_iterations", outer_iterations,
          "BFGS runs on a coarse-to-fine sigma schedule; probreg's gmmreg always runs 1");
        f("outer_tol", outer_tol, "stop the schedule when |f - f_prev| < outer_tol (probreg 1e-3)");
        f("maxiter", bfgs.maxiter, "BFGS iterations per run (probreg opt_maxiter 50)");
        f("gtol", bfgs.gtol, "BFGS stops when |grad|_inf <= gtol (probreg tol 1e-3, absolute)");
        f("gmm_max_iter", gmm_max_iter, "EM iterations of each GMM fit (sklearn 100)");
        f("gmm_tol", gmm_tol,
          "EM stops when the mean log-likelihood changes by < gmm_tol (sklearn 1e-3)");
        f("seed", seed, "seed of the k-means++ initialisation (sklearn's is unseeded in probreg)");
        sums.Fields(f,
                    "\"auto\": from approx_min_pairs = K_s * K_t on, both mixtures are merged per "
                    "cell of compress_cell_sigmas * sigma and pairs beyond sigma sqrt(2 ln(1 / "
                    "cutoff_tolerance)) are skipped (docs/performance.md: accuracy cost); "
                    "\"dense\": always exact",
                    "component pairs K_s * K_t from which kernel_sums=auto approximates");
    }
    void Validate(ParamCheck& c) const {
        AnnealedL2Options::Validate(c);
        c.AtLeast("n_gmm_components", n_gmm_components, 1);
        c.Above("sigma", sigma, 0.0);
        c.Finite("sigma", sigma);
        c.AtLeast("gmm_max_iter", gmm_max_iter, 1);
        c.AtLeast("gmm_tol", gmm_tol, 0.0);
        c.AtLeast("seed", seed, 0);
    }
    /// compat "probreg": probreg 0.3.7's defaults for these keys.
    void ApplyCompat() {
        if (compat != Compat::kProbreg) return;
        gmm = GmmFeatures::kSklearn;
        gradient = L2Gradient::kProbregHalf;
        normalize = false;
        bfgs.gtol = 0.001;
        bfgs.maxiter = 50;
    }
};

/// (mu, phi) of one cloud: sklearn-style spherical GMM or the points themselves.
MixtureFeatures Features(const GmmRegOptions& options, const PointCloud& P, int k,
                         std::mt19937_64& rng, int& em_iterations) {
    MixtureFeatures f;
    if (options.gmm == GmmFeatures::kPoints) {
        f.means = P;
        f.weights = Eigen::VectorXd::Constant(P.rows(), 1.0 / static_cast<double>(P.rows()));
        return f;
    }
    GmmFitOptions g;
    // K is set from the source; a smaller target gets at most one component per point.
    g.n_components = std::min<int>(k, static_cast<int>(P.rows()));
    g.max_iter = options.gmm_max_iter;
    g.tol = options.gmm_tol;
    const SphericalGmm gmm = FitSphericalGmm(P, g, rng);
    em_iterations += gmm.iterations;
    f.means = gmm.means;
    f.weights = gmm.weights;
    return f;
}

AlignResult AlignGmmReg(const GmmRegOptions& o, const PointCloud& source, const PointCloud& target,
                        const AlignContext& context) {
    // Bandwidth from the source only (probreg's _estimate_sigma).
    double sigma = o.use_estimated_sigma ? EstimateSigmaFromCovariance(source) : o.sigma;
    if (!(sigma > 0.0)) {
        throw std::runtime_error("gmmreg: source cloud is degenerate (sigma_est = 0)");
    }
    const L2Frame frame = o.normalize ? L2Frame::CenteredScaled(source, target, sigma) : L2Frame{};
    if (o.normalize) sigma = 1.0;
    const PointCloud Y = frame.SourceIn(source);
    const PointCloud X = frame.TargetIn(target);

    // Per-pair stream (AlignContext) mixed with the user's seed for the GMM fit's k-means++.
    std::mt19937_64 rng(SplitMix64(context.MethodSeed() ^ static_cast<std::uint64_t>(o.seed)));
    int em_iterations = 0;
    const int k =
        std::max(1, std::min(o.n_gmm_components, static_cast<int>(kComponentFraction * Y.rows())));
    MixtureFeatures fs = Features(o, Y, k, rng, em_iterations);
    MixtureFeatures ft = Features(o, X, k, rng, em_iterations);
    AlignResult result = AnnealedL2AlignResult(frame, MinimizeAnnealedL2(fs, ft, sigma, o));
    result.extra["components_source"] = fs.means.rows();
    result.extra["components_target"] = ft.means.rows();
    result.extra["gmm_em_iterations"] = em_iterations;
    return result;
}

}  // namespace

MethodInfo GmmRegMethodInfo() {
    MethodInfo info = MakeMethodInfo<GmmRegOptions>(
        "gmmreg",
        "GMMReg rigid as probreg runs it: spherical GMM features (k-means++/EM, seeded), L2 cost, "
        "scipy-like BFGS (More-Thuente); exact Gauss sums instead of IFGT (approximated at scale)",
        AlignGmmReg);
    info.paper_label = "GMMReg";  // the row of the OGMM paper's tables
    return info;
}

}  // namespace regbench
