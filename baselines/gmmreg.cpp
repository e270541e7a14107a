// GMMReg (Jian & Vemuri 2011) as probreg v0.3.7 runs it (probabilistic-baselines.md Sec. 2):
// fit a spherical GMM with K = min(800, floor(0.8 M)) components to each cloud, keep means and
// weights, minimise the rigid L2 cost f(theta) (Sec. 2 "Cost") with BFGS from the identity.
#include "baselines/gmmreg.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/bfgs.hpp"
#include "core/gmm_common.hpp"
#include "core/gmm_fit.hpp"
#include "core/gmm_l2.hpp"
#include "core/options.hpp"
#include "core/rng.hpp"

namespace regbench {
namespace {

constexpr char kName[] = "gmmreg";
/// probreg: n_gmm_components = min(n_gmm_components, int(0.8 M)).
constexpr double kComponentFraction = 0.8;

struct GmmRegOptions {
    std::string compat =
        "none";  ///< "none" (correct algorithm, default) | "probreg" (sets the defaults below)
    std::string gmm = "points";  ///< features: "sklearn" GMM fit (probreg) | "points" (mu = points)
    int n_gmm_components = 800;  ///< K = min(this, floor(0.8 M)), M = source size
    std::string gradient = "exact";   ///< "probreg_half" (1/2 of true, probreg) | "exact"
    bool normalize = true;            ///< optimise in a centred frame scaled by sigma
    double sigma = 1.0;               ///< bandwidth, used when use_estimated_sigma is false
    bool use_estimated_sigma = true;  ///< sigma = det(cov(source))^(1/6)
    double delta = 0.9;               ///< sigma *= delta between outer iterations, in (0, 1]
    int outer_iterations = 1;         ///< kernel-scale schedule steps (probreg: 1, no schedule)
    double outer_tol = 1e-3;          ///< stop the schedule when |f - f_prev| < outer_tol
    int maxiter = 200;                ///< BFGS iterations per outer iteration (probreg: 50)
    double gtol = 1e-6;               ///< BFGS |grad|_inf tolerance (probreg: 1e-3)
    int gmm_max_iter = 100;           ///< EM iterations (sklearn max_iter)
    double gmm_tol = 1e-3;            ///< EM lower-bound tolerance (sklearn tol)
    int seed = 0;                     ///< k-means++ seed of the GMM fits
    /// "auto": above approx_min_pairs = K_s * K_t, cell-compress both mixtures and cut the
    /// sums off at cutoff_tolerance (gmm_l2.hpp); "dense": always exact
    std::string kernel_sums = "auto";
    double approx_min_pairs = 1e8;      ///< K_s * K_t from which "auto" approximates
    double cutoff_tolerance = 1e-4;     ///< kernel value at the cutoff radius (4.29 sigma)
    double compress_cell_sigmas = 0.1;  ///< cell edge of the compression, in sigmas
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(GmmRegOptions,
                                                compat,
                                                gmm,
                                                n_gmm_components,
                                                gradient,
                                                normalize,
                                                sigma,
                                                use_estimated_sigma,
                                                delta,
                                                outer_iterations,
                                                outer_tol,
                                                maxiter,
                                                gtol,
                                                gmm_max_iter,
                                                gmm_tol,
                                                seed,
                                                kernel_sums,
                                                approx_min_pairs,
                                                cutoff_tolerance,
                                                compress_cell_sigmas)

/// Defaults (compat "none"): Jian & Vemuri's point features, the true gradient, a unit-free frame
/// and a tight gtol. compat "probreg" switches to probreg's values; explicit keys win.
GmmRegOptions ResolveOptions(const nlohmann::json& j) {
    GmmRegOptions o = ParseOptions<GmmRegOptions>(j, kName);
    RequireOneOf(o.compat, {"probreg", "none"}, kName, "compat");
    if (o.compat == "probreg") {
        auto unset = [&](const char* key) { return !j.is_object() || !j.contains(key); };
        if (unset("gmm")) o.gmm = "sklearn";
        if (unset("gradient")) o.gradient = "probreg_half";
        if (unset("normalize")) o.normalize = false;
        if (unset("gtol")) o.gtol = 1e-3;
        if (unset("maxiter")) o.maxiter = 50;
    }
    RequireOneOf(o.gmm, {"sklearn", "points"}, kName, "gmm");
    RequireOneOf(o.gradient, {"probreg_half", "exact"}, kName, "gradient");
    Require(o.n_gmm_components >= 1, kName, "n_gmm_components", "must be >= 1");
    Require(o.sigma > 0.0 && std::isfinite(o.sigma), kName, "sigma", "must be > 0");
    Require(o.delta > 0.0 && o.delta <= 1.0, kName, "delta", "must be in (0, 1]");
    Require(o.outer_iterations >= 1, kName, "outer_iterations", "must be >= 1");
    Require(o.outer_tol >= 0.0, kName, "outer_tol", "must be >= 0");
    Require(o.maxiter >= 0, kName, "maxiter", "must be >= 0");
    Require(o.gtol >= 0.0, kName, "gtol", "must be >= 0");
    Require(o.gmm_max_iter >= 1, kName, "gmm_max_iter", "must be >= 1");
    Require(o.gmm_tol >= 0.0, kName, "gmm_tol", "must be >= 0");
    Require(o.seed >= 0, kName, "seed", "must be >= 0");
    RequireOneOf(o.kernel_sums, {"auto", "dense"}, kName, "kernel_sums");
    Require(o.approx_min_pairs >= 0.0, kName, "approx_min_pairs", "must be >= 0");
    Require(o.cutoff_tolerance > 0.0 && o.cutoff_tolerance < 1.0, kName, "cutoff_tolerance",
            "must be in (0, 1)");
    Require(o.compress_cell_sigmas >= 0.0 && o.compress_cell_sigmas <= 1.0, kName,
            "compress_cell_sigmas", "must be in [0, 1] (0 = no compression)");
    return o;
}

class GmmRegMethod final : public RegistrationMethod {
public:
    explicit GmmRegMethod(GmmRegOptions options) : options_(std::move(options)) {}
    std::string Name() const override { return kName; }
    nlohmann::json Params() const override { return options_; }

protected:
    AlignResult DoAlign(const PointCloud& source,
                        const PointCloud& target,
                        const AlignContext& context) override {
        const GmmRegOptions& o = options_;
        // Bandwidth from the source only (probreg's _estimate_sigma).
        double sigma = o.use_estimated_sigma ? EstimateSigmaFromCovariance(source) : o.sigma;
        if (!(sigma > 0.0)) {
            throw std::runtime_error("gmmreg: source cloud is degenerate (sigma_est = 0)");
        }
        const L2Frame frame =
            o.normalize ? L2Frame::CenteredScaled(source, target, sigma) : L2Frame{};
        if (o.normalize) sigma = 1.0;
        const PointCloud Y = frame.SourceIn(source);
        const PointCloud X = frame.TargetIn(target);

        // Per-pair stream (AlignContext) mixed with the user's seed for the GMM fit's k-means++.
        std::mt19937_64 rng(SplitMix64(context.MethodSeed() ^ static_cast<std::uint64_t>(o.seed)));
        int em_iterations = 0;
        const int k = std::max(
            1, std::min(o.n_gmm_components, static_cast<int>(kComponentFraction * Y.rows())));
        const MixtureFeatures fs = Features(Y, k, rng, em_iterations);
        const MixtureFeatures ft = Features(X, k, rng, em_iterations);

        BfgsOptions bfgs;
        bfgs.maxiter = o.maxiter;
        bfgs.gtol = o.gtol;
        const L2Gradient gradient =
            o.gradient == "exact" ? L2Gradient::kExact : L2Gradient::kProbregHalf;
        Eigen::VectorXd theta = RigidGmmL2Cost::InitialTheta();
        AlignResult result;
        BfgsResult run;
        int outer = 0;
        double f_prev = 0.0;
        // probreg's L2DistRegistration.registration: BFGS, anneal sigma, stop on |df| < tol.
        L2SumOptions sums;
        sums.approximate = o.kernel_sums == "auto";
        sums.min_pairs = o.approx_min_pairs;
        sums.cutoff_tolerance = o.cutoff_tolerance;
        sums.compress_cell_sigmas = o.compress_cell_sigmas;
        bool approximated = false;
        for (outer = 1; outer <= o.outer_iterations; ++outer) {
            run = MinimizeRigidL2(fs, ft, sigma, gradient, theta, bfgs, sums, &approximated);
            result.iterations += run.iterations;
            theta = run.x;
            sigma *= o.delta;
            if (outer > 1 && std::abs(run.f - f_prev) < o.outer_tol) break;
            f_prev = run.f;
        }
        result.T_target_source = frame.ToInput(TransformFromTheta(theta));
        result.stop_reason = run.stop_reason;
        Convergence c{result.iterations, run.f, run.stop_reason};
        result.extra = c.ToJson();
        result.extra["outer_iterations"] = std::min(outer, o.outer_iterations);
        result.extra["evaluations"] = run.evaluations;
        result.extra["components_source"] = fs.means.rows();
        result.extra["components_target"] = ft.means.rows();
        result.extra["gmm_em_iterations"] = em_iterations;
        result.extra["approximated_sums"] = approximated;
        return result;
    }

private:
    /// (mu, phi) of one cloud: sklearn-style spherical GMM or the points themselves.
    MixtureFeatures Features(const PointCloud& P,
                             int k,
                             std::mt19937_64& rng,
                             int& em_iterations) const {
        MixtureFeatures f;
        if (options_.gmm == "points") {
            f.means = P;
            f.weights = Eigen::VectorXd::Constant(P.rows(), 1.0 / static_cast<double>(P.rows()));
            return f;
        }
        GmmFitOptions g;
        // K is set from the source; a smaller target gets at most one component per point.
        g.n_components = std::min<int>(k, static_cast<int>(P.rows()));
        g.max_iter = options_.gmm_max_iter;
        g.tol = options_.gmm_tol;
        const SphericalGmm gmm = FitSphericalGmm(P, g, rng);
        em_iterations += gmm.iterations;
        f.means = gmm.means;
        f.weights = gmm.weights;
        return f;
    }

    GmmRegOptions options_;
};

}  // namespace

MethodInfo GmmRegMethodInfo() {
    MethodInfo info;
    info.name = kName;
    info.summary =
        "GMMReg rigid as probreg runs it: spherical GMM features (k-means++/EM, seeded), L2 "
        "cost, scipy-like BFGS (More-Thuente); dense exact Gauss sums instead of IFGT";
    info.param_docs = {
        {"compat",
         "\"none\" (default, the correct algorithm: defaults become "
         "gmm=points, gradient=exact, normalize=true, gtol=1e-6, maxiter=200) or \"probreg\" "
         "(probreg v0.3.7 behaviour); explicit keys win"},
        {"gmm",
         "features: \"sklearn\" = GaussianMixture(K, spherical) means/weights (probreg), "
         "\"points\" = every point with weight 1/N (Jian & Vemuri, faster)"},
        {"n_gmm_components", "GMM components; K = min(this, floor(0.8 M)) from the source size M"},
        {"gradient",
         "\"probreg_half\" = probreg's gradient (exactly 1/2 of the true one), \"exact\""},
        {"normalize",
         "optimise with both clouds centred and divided by sigma (unit-free gtol); probreg: false"},
        {"sigma", "kernel bandwidth [input units], used only if use_estimated_sigma is false"},
        {"use_estimated_sigma", "sigma = det(cov(source))^(1/6) (probreg default true)"},
        {"delta", "sigma *= delta after each outer iteration, in (0, 1] (probreg 0.9)"},
        {"outer_iterations",
         "BFGS runs on a coarse-to-fine sigma schedule; probreg's gmmreg always runs 1"},
        {"outer_tol", "stop the schedule when |f - f_prev| < outer_tol (probreg 1e-3)"},
        {"maxiter", "BFGS iterations per run (probreg opt_maxiter 50)"},
        {"gtol", "BFGS stops when |grad|_inf <= gtol (probreg tol 1e-3, absolute)"},
        {"gmm_max_iter", "EM iterations of each GMM fit (sklearn 100)"},
        {"gmm_tol", "EM stops when the mean log-likelihood changes by < gmm_tol (sklearn 1e-3)"},
        {"seed", "seed of the k-means++ initialisation (sklearn's is unseeded in probreg)"},
        {"kernel_sums",
         "\"auto\": from approx_min_pairs = K_s * K_t on, both mixtures are merged per cell of "
         "compress_cell_sigmas * sigma and pairs beyond sigma sqrt(2 ln(1/cutoff_tolerance)) "
         "are skipped (docs/performance.md: accuracy cost); \"dense\": always exact"},
        {"approx_min_pairs", "component pairs K_s * K_t from which kernel_sums=auto approximates"},
        {"cutoff_tolerance", "kernel value at the cutoff radius, in (0, 1); 1e-4 -> 4.29 sigma"},
        {"compress_cell_sigmas", "cell edge of the compression in sigmas, [0, 1]; 0 = none"},
    };
    info.defaults = GmmRegOptions{};
    info.create = [](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        return std::make_unique<GmmRegMethod>(ResolveOptions(j));
    };
    return info;
}

}  // namespace regbench
