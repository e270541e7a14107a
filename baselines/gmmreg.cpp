// GMMReg (Jian & Vemuri 2011) as probreg v0.3.7 runs it (probabilistic-baselines.md Sec. 2):
// fit a spherical GMM with K = min(800, floor(0.8 M)) components to each cloud, keep means and
// weights, minimise the rigid L2 cost f(theta) (Sec. 2 "Cost") with BFGS from the identity.
#include "baselines/gmmreg.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/method_spec.hpp"
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
NLOHMANN_JSON_SERIALIZE_ENUM(GmmFeatures,
                             {{GmmFeatures::kSklearn, "sklearn"}, {GmmFeatures::kPoints, "points"}})

struct GmmRegOptions {  // each member documented once, in Spec()
    Compat compat = Compat::kNone;
    GmmFeatures gmm = GmmFeatures::kPoints;
    int n_gmm_components = 800;
    L2Gradient gradient = L2Gradient::kExact;
    bool normalize = true;
    double sigma = 1.0;
    bool use_estimated_sigma = true;
    double delta = 0.9;
    int outer_iterations = 1;
    double outer_tol = 1e-3;
    int maxiter = 200;
    double gtol = 1e-6;
    int gmm_max_iter = 100;
    double gmm_tol = 1e-3;
    int seed = 0;
    L2KernelSums kernel_sums = L2KernelSums::kAuto;
    double approx_min_pairs = 1e8;
    double cutoff_tolerance = 1e-4;
    double compress_cell_sigmas = 0.1;
};

const MethodSpec<GmmRegOptions>& Spec() {
    static const MethodSpec<GmmRegOptions> spec{
        kName,
        "GMMReg rigid as probreg runs it: spherical GMM features (k-means++/EM, seeded), L2 "
        "cost, scipy-like BFGS (More-Thuente); exact Gauss sums instead of IFGT (approximated at "
        "scale)",
        {
            Param("compat", &GmmRegOptions::compat,
                  "\"none\" (default, the correct algorithm: defaults become gmm=points, "
                  "gradient=exact, normalize=true, gtol=1e-6, maxiter=200) or \"probreg\" (probreg "
                  "v0.3.7 behaviour); explicit keys win"),
            Param("gmm", &GmmRegOptions::gmm,
                  "features: \"sklearn\" = GaussianMixture(K, spherical) means/weights (probreg), "
                  "\"points\" = every point with weight 1/N (Jian & Vemuri, faster)"),
            Param("n_gmm_components", &GmmRegOptions::n_gmm_components,
                  "GMM components; K = min(this, floor(0.8 M)) from the source size M")
                .AtLeast(1),
            Param("gradient", &GmmRegOptions::gradient,
                  "\"probreg_half\" = probreg's gradient (exactly 1/2 of the true one), \"exact\""),
            Param("normalize", &GmmRegOptions::normalize,
                  "optimise with both clouds centred and divided by sigma (unit-free gtol); "
                  "probreg: false"),
            Param("sigma", &GmmRegOptions::sigma,
                  "kernel bandwidth [input units], used only if use_estimated_sigma is false")
                .Greater(0.0)
                .Finite(),
            Param("use_estimated_sigma", &GmmRegOptions::use_estimated_sigma,
                  "sigma = det(cov(source))^(1/6) (probreg default true)"),
            Param("delta", &GmmRegOptions::delta,
                  "sigma *= delta after each outer iteration, in (0, 1] (probreg 0.9)")
                .Greater(0.0)
                .AtMost(1.0),
            Param("outer_iterations", &GmmRegOptions::outer_iterations,
                  "BFGS runs on a coarse-to-fine sigma schedule; probreg's gmmreg always runs 1")
                .AtLeast(1),
            Param("outer_tol", &GmmRegOptions::outer_tol,
                  "stop the schedule when |f - f_prev| < outer_tol (probreg 1e-3)")
                .AtLeast(0.0),
            Param("maxiter", &GmmRegOptions::maxiter,
                  "BFGS iterations per run (probreg opt_maxiter 50)")
                .AtLeast(0),
            Param("gtol", &GmmRegOptions::gtol,
                  "BFGS stops when |grad|_inf <= gtol (probreg tol 1e-3, absolute)")
                .AtLeast(0.0),
            Param("gmm_max_iter", &GmmRegOptions::gmm_max_iter,
                  "EM iterations of each GMM fit (sklearn 100)")
                .AtLeast(1),
            Param("gmm_tol", &GmmRegOptions::gmm_tol,
                  "EM stops when the mean log-likelihood changes by < gmm_tol (sklearn 1e-3)")
                .AtLeast(0.0),
            Param("seed", &GmmRegOptions::seed,
                  "seed of the k-means++ initialisation (sklearn's is unseeded in probreg)")
                .AtLeast(0),
            Param("kernel_sums", &GmmRegOptions::kernel_sums,
                  "\"auto\": from approx_min_pairs = K_s * K_t on, both mixtures are merged per "
                  "cell of compress_cell_sigmas * sigma and pairs beyond sigma sqrt(2 ln(1 / "
                  "cutoff_tolerance)) are skipped (docs/performance.md: accuracy cost); "
                  "\"dense\": always exact"),
            Param("approx_min_pairs", &GmmRegOptions::approx_min_pairs,
                  "component pairs K_s * K_t from which kernel_sums=auto approximates")
                .AtLeast(0.0),
            Param("cutoff_tolerance", &GmmRegOptions::cutoff_tolerance,
                  "kernel value at the cutoff radius, in (0, 1); 1e-4 -> 4.29 sigma")
                .Greater(0.0)
                .Below(1.0),
            Param("compress_cell_sigmas", &GmmRegOptions::compress_cell_sigmas,
                  "cell edge of the compression in sigmas, [0, 1]; 0 = none")
                .AtLeast(0.0)
                .AtMost(1.0),
        },
        nullptr,
        // compat "probreg": probreg v0.3.7's values for the keys the user did not give.
        {{"probreg",
          {{"gmm", "sklearn"},
           {"gradient", "probreg_half"},
           {"normalize", false},
           {"gtol", 1e-3},
           {"maxiter", 50}}}}};
    return spec;
}

/// (mu, phi) of one cloud: sklearn-style spherical GMM or the points themselves.
MixtureFeatures Features(const GmmRegOptions& options,
                         const PointCloud& P,
                         int k,
                         std::mt19937_64& rng,
                         int& em_iterations) {
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

AlignResult AlignGmmReg(const GmmRegOptions& o,
                        const PointCloud& source,
                        const PointCloud& target,
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
    const AnnealedL2Options anneal = AnnealedL2OptionsFrom(o);
    MixtureFeatures fs = Features(o, Y, k, rng, em_iterations);
    MixtureFeatures ft = Features(o, X, k, rng, em_iterations);
    AlignResult result = AnnealedL2AlignResult(frame, MinimizeAnnealedL2(fs, ft, sigma, anneal));
    result.extra["components_source"] = fs.means.rows();
    result.extra["components_target"] = ft.means.rows();
    result.extra["gmm_em_iterations"] = em_iterations;
    return result;
}

}  // namespace

MethodInfo GmmRegMethodInfo() { return MakeMethodInfo(Spec(), AlignGmmReg); }

}  // namespace regbench
