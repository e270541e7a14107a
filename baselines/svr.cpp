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

#include "baselines/schemas.hpp"
#include "core/math_constants.hpp"
#include "core/method_spec.hpp"
#include "gmm/bfgs.hpp"
#include "gmm/gmm_common.hpp"
#include "gmm/gmm_l2.hpp"

namespace regbench {
namespace {

constexpr char kName[] = "svr";
constexpr double kLibsvmCacheMb = 200.0;  // sklearn's OneClassSVM cache_size

void QuietLibsvm(const char*) {}

/// Documented in baselines/svr.schema.json (defaults too); the annealing, BFGS and
/// kernel-sum keys are the shared AnnealedL2MethodOptions base (gmm/gmm_l2.hpp).
struct SvrOptions : AnnealedL2MethodOptions {
    Compat compat;
    double nu;
    bool normalize;
    double sigma;
    double gamma;
    bool use_estimated_sigma;
    double gamma_delta;
    double svm_tol;
    int svm_max_points;
};
// clang-format off
REGBENCH_OPTION_FIELDS(SvrOptions, compat, nu, gradient, normalize, sigma, gamma,
                       use_estimated_sigma, delta, gamma_delta, outer_iterations, outer_tol, maxiter,
                       gtol, svm_tol, svm_max_points, kernel_sums, approx_min_pairs,
                       cutoff_tolerance, compress_cell_sigmas)
// clang-format on

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

AlignResult AlignSvr(const SvrOptions& o,
                     const PointCloud& source,
                     const PointCloud& target,
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

    const AnnealedL2Options anneal = AnnealedL2OptionsFrom(o);
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
    AlignResult result =
        AnnealedL2AlignResult(frame, MinimizeAnnealedL2(fs, ft, sigma, anneal, refit));
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
    return MakeMethodInfo(SpecOf<SvrOptions>(BaselineSchema("svr")), AlignSvr);
}

}  // namespace regbench
