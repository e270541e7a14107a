// GMMReg (Jian & Vemuri 2011) as probreg v0.3.7 runs it (probabilistic-baselines.md Sec. 2):
// fit a spherical GMM with K = min(800, floor(0.8 M)) components to each cloud, keep means and
// weights, minimise the rigid L2 cost f(theta) (Sec. 2 "Cost") with BFGS from the identity.
#include "baselines/gmmreg.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "baselines/schemas.hpp"
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

/// Documented in baselines/gmmreg.schema.json (defaults too); the annealing, BFGS and
/// kernel-sum keys are the shared AnnealedL2MethodOptions base (gmm/gmm_l2.hpp).
struct GmmRegOptions : AnnealedL2MethodOptions {
    Compat compat;
    GmmFeatures gmm;
    int n_gmm_components;
    bool normalize;
    double sigma;
    bool use_estimated_sigma;
    int gmm_max_iter;
    double gmm_tol;
    int seed;
};
// clang-format off
REGBENCH_OPTION_FIELDS(GmmRegOptions, compat, gmm, n_gmm_components, gradient, normalize, sigma,
                       use_estimated_sigma, delta, outer_iterations, outer_tol, maxiter, gtol,
                       gmm_max_iter, gmm_tol, seed, kernel_sums, approx_min_pairs, cutoff_tolerance,
                       compress_cell_sigmas)
// clang-format on

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

MethodInfo GmmRegMethodInfo() {
    return MakeMethodInfo(SpecOf<GmmRegOptions>(BaselineSchema("gmmreg")), AlignGmmReg);
}

}  // namespace regbench
