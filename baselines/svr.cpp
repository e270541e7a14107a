// SVR as probreg v0.3.7 runs it (probabilistic-baselines.md Sec. 3): per cloud a one-class
// nu-SVM (gamma = 1 / 2 sigma^2), mixture means = support vectors, weights
// phi = alpha (2 pi sigma^2)^(D/2); the GMMReg L2 cost and BFGS align the two mixtures.
#include "baselines/svr.hpp"

#include <libsvm/svm.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/bfgs.hpp"
#include "core/gmm_common.hpp"
#include "core/gmm_l2.hpp"
#include "core/options.hpp"

namespace regbench {
namespace {

constexpr char kName[] = "svr";
constexpr double kPi = 3.14159265358979323846;
constexpr double kLibsvmCacheMb = 200.0;  // sklearn's OneClassSVM cache_size

void QuietLibsvm(const char*) {}

struct SvrOptions {
    std::string compat =
        "none";       ///< "none" (correct algorithm, default) | "probreg" (sets the defaults below)
    double nu = 0.1;  ///< one-class nu in (0, 1]
    std::string gradient = "exact";   ///< "probreg_half" (probreg) | "exact"
    bool normalize = true;            ///< optimise in a centred frame scaled by sigma
    double sigma = 1.0;               ///< bandwidth when use_estimated_sigma is false
    double gamma = 0.5;               ///< RBF gamma when use_estimated_sigma is false
    bool use_estimated_sigma = true;  ///< sigma = sigma_est(source), gamma = 1 / (2 sigma^2)
    double delta = 0.9;               ///< cost sigma *= delta per outer iteration
    double gamma_delta = 10.0;        ///< probreg: SVM gamma *= gamma_delta per outer iteration
    int outer_iterations = 1;         ///< probreg's maxiter
    double outer_tol = 1e-3;          ///< probreg's tol on |f - f_prev|
    int maxiter = 200;                ///< BFGS iterations (probreg's opt_maxiter: 50)
    double gtol = 1e-6;               ///< BFGS |grad|_inf tolerance (probreg's opt_tol: 1e-3)
    double svm_tol = 1e-3;            ///< libsvm eps (sklearn tol)
    /// Clouds larger than this are fitted on a seeded uniform random subsample of this size
    /// (libsvm's SMO is ~quadratic in n); alphas are rescaled by n / subsample.
    int svm_max_points = 8000;
    std::string kernel_sums = "auto";   ///< as gmmreg: "auto" | "dense"
    double approx_min_pairs = 1e8;      ///< S_s * S_t from which "auto" approximates
    double cutoff_tolerance = 1e-4;     ///< kernel value at the cutoff radius
    double compress_cell_sigmas = 0.1;  ///< cell edge of the compression, in sigmas
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(SvrOptions,
                                                compat,
                                                nu,
                                                gradient,
                                                normalize,
                                                sigma,
                                                gamma,
                                                use_estimated_sigma,
                                                delta,
                                                gamma_delta,
                                                outer_iterations,
                                                outer_tol,
                                                maxiter,
                                                gtol,
                                                svm_tol,
                                                svm_max_points,
                                                kernel_sums,
                                                approx_min_pairs,
                                                cutoff_tolerance,
                                                compress_cell_sigmas)

SvrOptions ResolveOptions(const nlohmann::json& j) {
    SvrOptions o = ParseOptions<SvrOptions>(j, kName);
    RequireOneOf(o.compat, {"probreg", "none"}, kName, "compat");
    if (o.compat == "probreg") {
        auto unset = [&](const char* key) { return !j.is_object() || !j.contains(key); };
        if (unset("gradient")) o.gradient = "probreg_half";
        if (unset("normalize")) o.normalize = false;
        if (unset("gtol")) o.gtol = 1e-3;
        if (unset("maxiter")) o.maxiter = 50;
    }
    Require(o.nu > 0.0 && o.nu <= 1.0, kName, "nu", "must be in (0, 1]");
    RequireOneOf(o.gradient, {"probreg_half", "exact"}, kName, "gradient");
    Require(o.sigma > 0.0 && std::isfinite(o.sigma), kName, "sigma", "must be > 0");
    Require(o.gamma > 0.0 && std::isfinite(o.gamma), kName, "gamma", "must be > 0");
    Require(o.delta > 0.0 && o.delta <= 1.0, kName, "delta", "must be in (0, 1]");
    Require(o.gamma_delta > 0.0 && std::isfinite(o.gamma_delta), kName, "gamma_delta",
            "must be > 0");
    Require(o.outer_iterations >= 1, kName, "outer_iterations", "must be >= 1");
    Require(o.outer_tol >= 0.0, kName, "outer_tol", "must be >= 0");
    Require(o.maxiter >= 0, kName, "maxiter", "must be >= 0");
    Require(o.gtol >= 0.0, kName, "gtol", "must be >= 0");
    Require(o.svm_tol > 0.0, kName, "svm_tol", "must be > 0");
    Require(o.svm_max_points >= 10, kName, "svm_max_points", "must be >= 10");
    RequireOneOf(o.kernel_sums, {"auto", "dense"}, kName, "kernel_sums");
    Require(o.approx_min_pairs >= 0.0, kName, "approx_min_pairs", "must be >= 0");
    Require(o.cutoff_tolerance > 0.0 && o.cutoff_tolerance < 1.0, kName, "cutoff_tolerance",
            "must be in (0, 1)");
    Require(o.compress_cell_sigmas >= 0.0 && o.compress_cell_sigmas <= 1.0, kName,
            "compress_cell_sigmas", "must be in [0, 1] (0 = no compression)");
    return o;
}

/// Mixture from an OC-SVM: mu = support vectors, phi = alpha (2 pi sigma^2)^(D/2) (probreg's
/// features.OneClassSVM.compute; the weights are not normalised).
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
MixtureFeatures SvmFeatures(const PointCloud& full,
                            double nu,
                            double gamma,
                            double phi_sigma,
                            double tol,
                            Eigen::Index max_points,
                            std::mt19937_64& rng) {
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

class SvrMethod final : public RegistrationMethod {
public:
    explicit SvrMethod(SvrOptions options) : options_(std::move(options)) {}
    std::string Name() const override { return kName; }
    nlohmann::json Params() const override { return options_; }

protected:
    AlignResult DoAlign(const PointCloud& source,
                        const PointCloud& target,
                        const AlignContext& context) override {
        const SvrOptions& o = options_;
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
        const L2Frame frame =
            o.normalize ? L2Frame::CenteredScaled(source, target, sigma) : L2Frame{};
        if (o.normalize) {
            gamma *= sigma * sigma;  // same kernel in the scaled frame
            sigma = 1.0;
        }
        const PointCloud Y = frame.SourceIn(source);
        const PointCloud X = frame.TargetIn(target);
        const double phi_sigma = sigma;  // probreg's feature sigma is never annealed
        const bool probreg = o.compat == "probreg";

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
        Eigen::Index sv_source = 0, sv_target = 0;
        L2SumOptions sums;
        sums.approximate = o.kernel_sums == "auto";
        sums.min_pairs = o.approx_min_pairs;
        sums.cutoff_tolerance = o.cutoff_tolerance;
        sums.compress_cell_sigmas = o.compress_cell_sigmas;
        bool approximated = false;
        for (outer = 1; outer <= o.outer_iterations; ++outer) {
            // probreg refits both SVMs each outer step with gamma *= 10 while phi keeps the
            // first sigma and the cost uses sigma * 0.9^k (inconsistent). "none" keeps
            // gamma = 1 / 2 sigma^2 and phi consistent with the annealed sigma.
            const double fs_sigma = probreg ? phi_sigma : sigma;
            const MixtureFeatures fs =
                SvmFeatures(Y, o.nu, gamma, fs_sigma, o.svm_tol, o.svm_max_points, rng);
            const MixtureFeatures ft =
                SvmFeatures(X, o.nu, gamma, fs_sigma, o.svm_tol, o.svm_max_points, rng);
            sv_source = fs.means.rows();
            sv_target = ft.means.rows();
            run = MinimizeRigidL2(fs, ft, sigma, gradient, theta, bfgs, sums, &approximated);
            result.iterations += run.iterations;
            theta = run.x;
            sigma *= o.delta;
            gamma = probreg ? gamma * o.gamma_delta : 1.0 / (2.0 * sigma * sigma);
            if (outer > 1 && std::abs(run.f - f_prev) < o.outer_tol) break;
            f_prev = run.f;
        }
        result.T_target_source = frame.ToInput(TransformFromTheta(theta));
        result.stop_reason = run.stop_reason;
        Convergence c{result.iterations, run.f, run.stop_reason};
        result.extra = c.ToJson();
        result.extra["outer_iterations"] = std::min(outer, o.outer_iterations);
        result.extra["evaluations"] = run.evaluations;
        result.extra["support_vectors_source"] = sv_source;
        result.extra["support_vectors_target"] = sv_target;
        result.extra["approximated_sums"] = approximated;
        result.extra["svm_subsampled"] =
            std::max(Y.rows(), X.rows()) > static_cast<Eigen::Index>(o.svm_max_points);
        return result;
    }

private:
    SvrOptions options_;
};

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
    MethodInfo info;
    info.name = kName;
    info.summary =
        "Support Vector Registration rigid as probreg runs it: libsvm one-class nu-SVM per "
        "cloud (support vectors = GMM means), L2 cost, scipy-like BFGS; dense exact Gauss sums";
    info.param_docs = {
        {"compat",
         "\"none\" (default, correct: gradient=exact, normalize=true, gtol=1e-6, maxiter=200, "
         "consistent sigma schedule) or \"probreg\" (probreg v0.3.7, incl. its gamma*=10 "
         "annealing); explicit keys win"},
        {"nu", "one-class SVM nu in (0, 1]: fraction bound on outliers / support vectors (0.1)"},
        {"gradient", "\"probreg_half\" = probreg's gradient (1/2 of the true one), \"exact\""},
        {"normalize", "optimise with both clouds centred and divided by sigma; probreg: false"},
        {"sigma", "bandwidth [input units] when use_estimated_sigma is false (probreg 1.0)"},
        {"gamma", "RBF gamma when use_estimated_sigma is false (probreg 0.5)"},
        {"use_estimated_sigma", "sigma = det(cov(source))^(1/6), gamma = 1/(2 sigma^2) (true)"},
        {"delta", "cost sigma *= delta per outer iteration, in (0, 1] (probreg 0.9)"},
        {"gamma_delta", "compat probreg: SVM gamma *= gamma_delta per outer iteration (10)"},
        {"outer_iterations", "outer loop steps, SVMs refitted each step (probreg maxiter 1)"},
        {"outer_tol", "stop the outer loop when |f - f_prev| < outer_tol (probreg tol 1e-3)"},
        {"maxiter", "BFGS iterations per outer step (probreg opt_maxiter 50)"},
        {"gtol", "BFGS stops when |grad|_inf <= gtol (probreg opt_tol 1e-3)"},
        {"svm_tol", "libsvm stopping tolerance eps (sklearn tol 1e-3)"},
        {"svm_max_points",
         "fit each one-class SVM on a seeded random subsample of this many points when the "
         "cloud is larger (alphas scaled by n / subsample); >= 10"},
        {"kernel_sums",
         "\"auto\": from approx_min_pairs support-vector pairs on, cell-compressed mixtures and "
         "a kd-tree cutoff (as gmmreg); \"dense\": always exact"},
        {"approx_min_pairs", "S_s * S_t from which kernel_sums=auto approximates"},
        {"cutoff_tolerance", "kernel value at the cutoff radius, in (0, 1); 1e-4 -> 4.29 sigma"},
        {"compress_cell_sigmas", "cell edge of the compression in sigmas, [0, 1]; 0 = none"},
    };
    info.defaults = SvrOptions{};
    info.create = [](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        return std::make_unique<SvrMethod>(ResolveOptions(j));
    };
    return info;
}

}  // namespace regbench
