// SVR as probreg v0.3.7 runs it (probabilistic-baselines.md Sec. 3): per cloud a one-class
// nu-SVM (gamma = 1 / 2 sigma^2), mixture means = support vectors, weights
// phi = alpha (2 pi sigma^2)^(D/2); the GMMReg L2 cost and BFGS align the two mixtures.
#include "baselines/svr.hpp"

#include <libsvm/svm.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <random>
#include <stdexcept>
#include <string>

#include "core/math_constants.hpp"
#include "core/params.hpp"
#include "gmm/bfgs.hpp"
#include "gmm/gmm_common.hpp"
#include "gmm/gmm_l2.hpp"

namespace regbench {
namespace {

constexpr char kName[] = "svr";
constexpr double kLibsvmCacheMb = 200.0;  // sklearn's OneClassSVM cache_size

void QuietLibsvm(const char*) {}

/// Options of `svr`; the annealing, BFGS and kernel-sum fields are the shared
/// AnnealedL2Options base (gmm/gmm_l2.hpp), bound here with svr's docs.
struct SvrOptions : AnnealedL2Options {
    Compat compat = Compat::kNone;  ///< "none" or "probreg"
    /// one-class SVM nu: fraction bound on outliers / support vectors (0.1)
    double nu = 0.1;
    bool normalize = true;  ///< optimise with both clouds centred and divided by sigma
    /// bandwidth [input units] when use_estimated_sigma is false (probreg 1.0)
    double sigma = 1.0;
    double gamma = 0.5;  ///< RBF gamma when use_estimated_sigma is false (probreg 0.5)
    /// sigma = det(cov(source))^(1/6), gamma = 1/(2 sigma^2) (true)
    bool use_estimated_sigma = true;
    /// compat probreg: SVM gamma *= gamma_delta per outer iteration (10)
    double gamma_delta = 10.0;
    double svm_tol = 0.001;  ///< libsvm stopping tolerance eps (sklearn tol 1e-3)
    /// fit each one-class SVM on a seeded random subsample of this many points when the cloud is
    /// larger (alphas scaled by n / subsample)
    int svm_max_points = 8000;

    template <class F>
    void Fields(F&& f) {
        f("compat", compat,
          "\"none\" (default, correct: gradient=exact, normalize=true, gtol=1e-6, maxiter=200, "
          "consistent sigma schedule) or \"probreg\" (probreg v0.3.7, incl. its gamma*=10 "
          "annealing); explicit keys win");
        f("nu", nu, "one-class SVM nu: fraction bound on outliers / support vectors (0.1)");
        f("gradient", gradient,
          "\"probreg_half\" = probreg's gradient (1/2 of the true one), \"exact\"");
        f("normalize", normalize,
          "optimise with both clouds centred and divided by sigma; probreg: false");
        f("sigma", sigma,
          "bandwidth [input units] when use_estimated_sigma is false (probreg 1.0)");
        f("gamma", gamma, "RBF gamma when use_estimated_sigma is false (probreg 0.5)");
        f("use_estimated_sigma", use_estimated_sigma,
          "sigma = det(cov(source))^(1/6), gamma = 1/(2 sigma^2) (true)");
        f("delta", delta, "cost sigma *= delta per outer iteration (probreg 0.9)");
        f("gamma_delta", gamma_delta,
          "compat probreg: SVM gamma *= gamma_delta per outer iteration (10)");
        f("outer_iterations", outer_iterations,
          "outer loop steps, SVMs refitted each step (probreg maxiter 1)");
        f("outer_tol", outer_tol,
          "stop the outer loop when |f - f_prev| < outer_tol (probreg tol 1e-3)");
        f("maxiter", bfgs.maxiter, "BFGS iterations per outer step (probreg opt_maxiter 50)");
        f("gtol", bfgs.gtol, "BFGS stops when |grad|_inf <= gtol (probreg opt_tol 1e-3)");
        f("svm_tol", svm_tol, "libsvm stopping tolerance eps (sklearn tol 1e-3)");
        f("svm_max_points", svm_max_points,
          "fit each one-class SVM on a seeded random subsample of this many points when the cloud "
          "is larger (alphas scaled by n / subsample)");
        sums.Fields(f,
                    "\"auto\": from approx_min_pairs support-vector pairs on, cell-compressed "
                    "mixtures and a kd-tree cutoff (as gmmreg); \"dense\": always exact",
                    "S_s * S_t from which kernel_sums=auto approximates");
    }
    void Validate(ParamCheck& c) const {
        AnnealedL2Options::Validate(c);
        c.Above("nu", nu, 0.0);
        c.AtMost("nu", nu, 1.0);
        c.Above("sigma", sigma, 0.0);
        c.Finite("sigma", sigma);
        c.Above("gamma", gamma, 0.0);
        c.Finite("gamma", gamma);
        c.Above("gamma_delta", gamma_delta, 0.0);
        c.Finite("gamma_delta", gamma_delta);
        c.Above("svm_tol", svm_tol, 0.0);
        c.AtLeast("svm_max_points", svm_max_points, 10);
    }
    /// compat "probreg": probreg 0.3.7's defaults for these keys.
    void ApplyCompat() {
        if (compat != Compat::kProbreg) return;
        gradient = L2Gradient::kProbregHalf;
        normalize = false;
        bfgs.gtol = 0.001;
        bfgs.maxiter = 50;
    }
};

/// A seeded uniform random subset of `max_points` rows (all rows when the cloud is smaller),
/// in increasing row order.
PointCloud SubsampleRows(const PointCloud& P, Eigen::Index max_points, std::mt19937_64& rng) {
    if (P.rows() <= max_points) return P;
    std::vector<Eigen::Index> idx(static_cast<size_t>(P.rows()));
    for (size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<Eigen::Index>(i);
    // Partial Fisher-Yates with the portable UniformInt-free draw: rng() % range is fine here
    // (range << 2^64: the bias is < 1e-13).
    for (Eigen::Index k = 0; k < max_points; ++k) {
        const auto range = static_cast<std::uint64_t>(P.rows() - k);
        std::swap(idx[static_cast<size_t>(k)],
                  idx[static_cast<size_t>(k + static_cast<Eigen::Index>(rng() % range))]);
    }
    idx.resize(static_cast<size_t>(max_points));
    std::sort(idx.begin(), idx.end());
    PointCloud out(max_points, 3);
    for (Eigen::Index k = 0; k < max_points; ++k) out.row(k) = P.row(idx[static_cast<size_t>(k)]);
    return out;
}

/// Mixture from an OC-SVM: mu = support vectors, phi = alpha (2 pi sigma^2)^(D/2) (probreg's
/// features.OneClassSVM.compute; the weights are not normalised). Above svm_max_points the SVM
/// is fitted on a random subsample and alpha scaled by n / subsample, so sum(alpha) = nu n as
/// for a full fit and the two clouds' weights stay comparable.
MixtureFeatures SvmFeatures(const PointCloud& full, double nu, double gamma, double phi_sigma,
                            double tol, Eigen::Index max_points, std::mt19937_64& rng) {
    const PointCloud P = SubsampleRows(full, max_points, rng);
    const OneClassSvm svm = FitOneClassSvm(P, nu, gamma, tol);
    MixtureFeatures f;
    f.means.resize(static_cast<Eigen::Index>(svm.support.size()), 3);
    for (size_t i = 0; i < svm.support.size(); ++i) {
        f.means.row(static_cast<Eigen::Index>(i)) = P.row(svm.support[i]);
    }
    const double rescale = static_cast<double>(full.rows()) / static_cast<double>(P.rows());
    f.weights = rescale * svm.alpha * std::pow(2.0 * kPi * phi_sigma * phi_sigma, 1.5);
    return f;
}

AlignResult AlignSvr(const SvrOptions& o, const PointCloud& source, const PointCloud& target,
                     const AlignContext& context) {
    std::mt19937_64 rng = context.MakeRng();  // the SVM subsample, when one is drawn
    double sigma = o.sigma;
    double gamma = o.gamma;
    if (o.use_estimated_sigma) {
        sigma = EstimateSigmaFromCovariance(source);
        if (!(sigma > 0.0)) {
            throw std::runtime_error("svr: source cloud is degenerate (sigma_est = 0)");
        }
        gamma = 1.0 / (2.0 * sigma * sigma);  // overrides the gamma parameter
    }
    const L2Frame frame = o.normalize ? L2Frame::CenteredScaled(source, target, sigma) : L2Frame{};
    if (o.normalize) {
        gamma *= sigma * sigma;  // same kernel in the scaled frame
        sigma = 1.0;
    }
    const PointCloud Y = frame.SourceIn(source);
    const PointCloud X = frame.TargetIn(target);
    const double phi_sigma = sigma;  // probreg's feature sigma is never annealed
    const bool probreg = o.compat == Compat::kProbreg;

    Eigen::Index sv_source = 0, sv_target = 0;
    bool first_step = true;
    // probreg refits both SVMs each outer step with gamma *= 10 while phi keeps the first
    // sigma and the cost uses sigma * 0.9^k (inconsistent). "none" keeps gamma = 1 / 2
    // sigma^2 and phi consistent with the annealed sigma.
    const RefitMixtures refit = [&](double step_sigma, MixtureFeatures& fs, MixtureFeatures& ft) {
        if (!first_step) {
            gamma = probreg ? gamma * o.gamma_delta : 1.0 / (2.0 * step_sigma * step_sigma);
        }
        first_step = false;
        const double fs_sigma = probreg ? phi_sigma : step_sigma;
        fs = SvmFeatures(Y, o.nu, gamma, fs_sigma, o.svm_tol, o.svm_max_points, rng);
        ft = SvmFeatures(X, o.nu, gamma, fs_sigma, o.svm_tol, o.svm_max_points, rng);
        sv_source = fs.means.rows();
        sv_target = ft.means.rows();
    };
    MixtureFeatures fs, ft;
    AlignResult result = AnnealedL2AlignResult(frame, MinimizeAnnealedL2(fs, ft, sigma, o, refit));
    result.extra["support_vectors_source"] = sv_source;
    result.extra["support_vectors_target"] = sv_target;
    result.extra["svm_subsampled"] =
        std::max(Y.rows(), X.rows()) > static_cast<Eigen::Index>(o.svm_max_points);
    return result;
}

}  // namespace

OneClassSvm FitOneClassSvm(const PointCloud& X, double nu, double gamma, double tol) {
    if (!(nu > 0.0 && nu <= 1.0)) throw std::invalid_argument("FitOneClassSvm: nu not in (0, 1]");
    if (!(gamma > 0.0)) throw std::invalid_argument("FitOneClassSvm: gamma must be > 0");
    if (!(tol > 0.0)) throw std::invalid_argument("FitOneClassSvm: tol must be > 0");
    const int n = static_cast<int>(X.rows());
    if (n < 1) throw std::invalid_argument("FitOneClassSvm: empty cloud");
    static std::once_flag quiet;  // libsvm prints through a process-wide hook
    std::call_once(quiet, [] { svm_set_print_string_function(&QuietLibsvm); });

    // Dense rows (index 1..3, then -1); libsvm's model points into these, so they outlive it.
    std::vector<svm_node> nodes(static_cast<size_t>(n) * 4);
    std::vector<svm_node*> rows(static_cast<size_t>(n));
    std::vector<double> labels(static_cast<size_t>(n), 1.0);
    for (int i = 0; i < n; ++i) {
        svm_node* r = &nodes[static_cast<size_t>(i) * 4];
        for (int d = 0; d < 3; ++d) r[d] = svm_node{d + 1, X(i, d)};
        r[3] = svm_node{-1, 0.0};
        rows[static_cast<size_t>(i)] = r;
    }
    svm_problem problem{n, labels.data(), rows.data()};
    svm_parameter param{};
    param.svm_type = ONE_CLASS;
    param.kernel_type = RBF;
    param.degree = 3;
    param.gamma = gamma;
    param.coef0 = 0.0;
    param.cache_size = kLibsvmCacheMb;
    param.eps = tol;
    param.C = 1.0;
    param.nr_weight = 0;
    param.nu = nu;
    param.p = 0.1;
    param.shrinking = 1;
    param.probability = 0;
    if (const char* error = svm_check_parameter(&problem, &param)) {
        throw std::invalid_argument(std::string("FitOneClassSvm: libsvm: ") + error);
    }
    std::unique_ptr<svm_model, void (*)(svm_model*)> model(
        svm_train(&problem, &param), [](svm_model* m) { svm_free_and_destroy_model(&m); });
    OneClassSvm out;
    // libsvm's one-class dual: 0 <= alpha <= 1, sum alpha = nu n (sklearn's dual_coef_ as is).
    out.support.resize(static_cast<size_t>(model->l));
    out.alpha.resize(model->l);
    for (int i = 0; i < model->l; ++i) {
        out.support[static_cast<size_t>(i)] = model->sv_indices[i] - 1;  // 1-based
        out.alpha[i] = model->sv_coef[0][i];
    }
    out.rho = model->rho[0];
    return out;
}

MethodInfo SvrMethodInfo() {
    MethodInfo info = MakeMethodInfo<SvrOptions>(
        "svr",
        "Support Vector Registration rigid as probreg runs it: libsvm one-class nu-SVM per cloud "
        "(support vectors = GMM means), L2 cost, scipy-like BFGS; exact Gauss sums (approximated "
        "at scale)",
        AlignSvr);
    info.paper_label = "SVR";  // the row of the OGMM paper's tables
    return info;
}

}  // namespace regbench
