#include "baselines/cpd.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>

#include "core/gauss_sum.hpp"
#include "core/gmm_common.hpp"
#include "core/kabsch.hpp"
#include "core/options.hpp"
#include "core/transform.hpp"

namespace regbench {

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(CpdOptions,
                                                w,
                                                maxiter,
                                                tol,
                                                update_scale,
                                                sigma2_formula,
                                                sigma2,
                                                compat,
                                                e_step,
                                                truncation_sigmas,
                                                truncation_min_points,
                                                cluster_cell_sigmas,
                                                cluster_min_points)

namespace {

constexpr const char* kName = "cpd";
constexpr int kDim = 3;
/// probreg's floor for sigma^2 (np.finfo(np.float32).eps): keeps ln(sigma^2) and 1/sigma^2
/// finite once a clean pair has converged exactly.
constexpr double kSigma2Floor = 1.19e-7;

/// One M-step's outputs (spec section 1, "M-step").
struct MStep {
    Transform T = Transform::Identity();
    double scale = 1.0;
    double sigma2 = 0.0;
    double q = 0.0;
};

/// CPD M-step on the original source Y (Myronenko & Song 2010, Fig. 2, rigid), with probreg's
/// sigma^2 variants.
MStep MaximizationStep(const PointCloud& Y,
                       const PointCloud& X,
                       const CpdPosteriors& post,
                       bool update_scale,
                       bool probreg_sigma2) {
    const double np = post.np;
    const Eigen::Vector3d mu_x = post.px.colwise().sum().transpose() / np;
    const Eigen::Vector3d mu_y = (Y.transpose() * post.p1) / np;
    const PointCloud yc = Y.rowwise() - mu_y.transpose();
    // A = PX^T Yc - mu_x (p1^T Yc)
    const Eigen::Matrix3d A = post.px.transpose() * yc - mu_x * (post.p1.transpose() * yc);
    const double b = (yc.rowwise().squaredNorm().transpose() * post.p1).value();
    const ProcrustesResult fit = ProcrustesFromMoments(mu_y, mu_x, A, b, update_scale);
    if (!fit.valid) throw std::runtime_error("M-step produced a non-finite rotation");
    const double a = (A.transpose() * fit.R).trace();
    const double cx =
        ((X.rowwise() - mu_x.transpose()).rowwise().squaredNorm().transpose() * post.pt1).value();

    MStep out;
    out.scale = update_scale ? a / b : 1.0;
    out.T = MakeTransform(out.scale * fit.R, mu_x - out.scale * fit.R * mu_y);
    const double s = out.scale;
    double sigma2 = 0.0;
    if (probreg_sigma2) {
        // probreg: (cx - s a) with scale, (cx + b - a) without: the latter is its bug.
        sigma2 = update_scale ? (cx - s * a) / (np * kDim) : (cx + b - a) / (np * kDim);
    } else {
        sigma2 = (cx - 2.0 * s * a + s * s * b) / (np * kDim);  // maximum likelihood
    }
    out.sigma2 = std::max(sigma2, kSigma2Floor);
    out.q = (cx - 2.0 * s * a + s * s * b) / (2.0 * out.sigma2) +
            kDim * np * 0.5 * std::log(out.sigma2);
    return out;
}

class CpdMethod final : public RegistrationMethod {
public:
    explicit CpdMethod(CpdOptions options) : options_(std::move(options)) {}
    std::string Name() const override { return kName; }
    nlohmann::json Params() const override { return options_; }

protected:
    bool AllowsScale() const override { return options_.update_scale; }

    AlignResult DoAlign(const PointCloud& Y,
                        const PointCloud& X,
                        const AlignContext& /*context*/) override {
        const double m = static_cast<double>(Y.rows());
        const double n = static_cast<double>(X.rows());
        GaussSumOptions gs;
        gs.mode = ParseGaussSumMode(options_.e_step, "cpd: parameter 'e_step'");
        gs.truncation_sigmas = options_.truncation_sigmas;
        gs.truncation_min_points = options_.truncation_min_points;
        gs.cluster_cell_sigmas = options_.cluster_cell_sigmas;
        gs.cluster_min_points = options_.cluster_min_points;
        CpdEStep e_step(Y, X, gs);
        const bool probreg_sigma2 = options_.sigma2_formula == "probreg";

        // Init (spec section 1): R = I, t = 0, s = 1, sigma^2 = sqsum, q0 = 1 + N D/2 ln sigma^2.
        MStep state;
        state.sigma2 = options_.sigma2 > 0.0 ? options_.sigma2 : SquaredDistanceMean(Y, X);
        state.sigma2 = std::max(state.sigma2, kSigma2Floor);
        state.q = 1.0 + n * kDim * 0.5 * std::log(state.sigma2);

        Convergence conv;
        conv.stop_reason = "max_iterations";
        CpdPosteriors post;
        int truncated_iterations = 0;
        int compressed_iterations = 0;
        std::int64_t evaluated_pairs = 0;
        for (int it = 1; it <= options_.maxiter; ++it) {
            // c = (2 pi sigma^2)^(D/2) w/(1-w) M/N: the uniform outlier term (CPD eq. (7)).
            const double c = std::pow(2.0 * M_PI * state.sigma2, 0.5 * kDim) * options_.w /
                             (1.0 - options_.w) * m / n;
            e_step.Compute(state.T, state.sigma2, c, post);
            truncated_iterations += post.truncated ? 1 : 0;
            compressed_iterations += post.compressed_cells > 0 ? 1 : 0;
            evaluated_pairs += post.evaluated_pairs;
            if (!(post.np > 0.0)) {
                conv.stop_reason = "no_correspondences";  // keep the previous transform
                break;
            }
            const MStep next = MaximizationStep(Y, X, post, options_.update_scale, probreg_sigma2);
            const double dq = std::abs(next.q - state.q);
            state = next;
            conv.iterations = it;
            if (dq < options_.tol) {
                conv.stop_reason = "converged";
                break;
            }
        }
        conv.objective = state.q;

        AlignResult r;
        r.T_target_source = state.T;
        r.iterations = conv.iterations;
        r.stop_reason = conv.stop_reason;
        r.scale = state.scale;
        r.extra = conv.ToJson();
        r.extra["sigma2"] = state.sigma2;
        r.extra["scale"] = state.scale;
        r.extra["truncated_iterations"] = truncated_iterations;
        r.extra["compressed_iterations"] = compressed_iterations;
        r.extra["kernel_evaluations"] = evaluated_pairs;
        return r;
    }

private:
    CpdOptions options_;
};

}  // namespace

CpdOptions ParseCpdOptions(const nlohmann::json& j) {
    CpdOptions o = ParseOptions<CpdOptions>(j, kName);
    RequireOneOf(o.compat, {"none", "probreg"}, kName, "compat");
    const bool given = j.is_object();
    if (o.compat == "probreg") {
        if (!given || !j.contains("update_scale")) o.update_scale = true;
        if (!given || !j.contains("sigma2_formula")) o.sigma2_formula = "probreg";
    }
    Require(o.w >= 0.0 && o.w < 1.0, kName, "w", "must be in [0, 1), got " + std::to_string(o.w));
    Require(o.maxiter >= 1, kName, "maxiter", "must be >= 1, got " + std::to_string(o.maxiter));
    Require(o.tol >= 0.0 && std::isfinite(o.tol), kName, "tol",
            "must be finite and >= 0, got " + std::to_string(o.tol));
    RequireOneOf(o.sigma2_formula, {"ml", "probreg"}, kName, "sigma2_formula");
    Require(o.sigma2 >= 0.0 && std::isfinite(o.sigma2), kName, "sigma2",
            "must be > 0, or 0 for sqsum(Y, X); got " + std::to_string(o.sigma2));
    RequireOneOf(o.e_step, {"auto", "dense", "truncated"}, kName, "e_step");
    Require(o.truncation_sigmas > 0.0 && std::isfinite(o.truncation_sigmas), kName,
            "truncation_sigmas", "must be > 0, got " + std::to_string(o.truncation_sigmas));
    Require(o.truncation_min_points >= 0, kName, "truncation_min_points",
            "must be >= 0, got " + std::to_string(o.truncation_min_points));
    Require(
        o.cluster_cell_sigmas >= 0.0 && o.cluster_cell_sigmas <= 1.0, kName, "cluster_cell_sigmas",
        "must be in [0, 1] (0 disables compression), got " + std::to_string(o.cluster_cell_sigmas));
    Require(o.cluster_min_points >= 0, kName, "cluster_min_points",
            "must be >= 0, got " + std::to_string(o.cluster_min_points));
    return o;
}

MethodInfo CpdMethodInfo() {
    MethodInfo info;
    info.name = kName;
    info.summary =
        "rigid Coherent Point Drift (Myronenko & Song 2010) per probreg 0.3.7; fused float "
        "SIMD E-step (kd-leaf pruning, optional 4-sigma truncation), double M-step";
    info.param_docs = {
        {"w", "weight of the uniform outlier component, in [0, 1); probreg default 0"},
        {"maxiter", "maximum EM iterations (>= 1); probreg 50"},
        {"tol", "stop when |q - q_prev| < tol, absolute on the objective q; probreg 1e-3"},
        {"update_scale",
         "estimate a scale s (similarity transform); default false, true under compat=probreg"},
        {"sigma2_formula",
         "\"ml\": (cx - 2sa + s^2 b)/(Np D); \"probreg\": (cx + b - a)/(Np D) without scale "
         "(probreg's bug, sigma^2 stalls); default ml, probreg under compat=probreg"},
        {"sigma2", "initial sigma^2 (> 0); 0 = sqsum(Y, X) as probreg"},
        {"compat",
         "\"none\" (correct rigid CPD) or \"probreg\" (update_scale=true and probreg's sigma^2 "
         "formula unless those are given explicitly)"},
        {"e_step",
         "\"auto\" (dense or cell-compressed, truncated once the switch rule holds), \"dense\" "
         "(exact up to float "
         "underflow) or \"truncated\" (always r = truncation_sigmas * sigma)"},
        {"truncation_sigmas", "truncated E-step radius in sigmas (> 0); 4 -> edge kernel 3.4e-4"},
        {"truncation_min_points",
         "auto: truncate only if max(M, N) >= this and r < 1/4 of the target bbox diagonal"},
        {"cluster_cell_sigmas",
         "auto, at scale: while a cloud has under half as many cells of edge "
         "cluster_cell_sigmas * sigma as points, each E-step pass sums over its cells' weighted "
         "centroids (docs/performance.md: accuracy cost); 0 = never"},
        {"cluster_min_points", "auto: compress only if max(M, N) >= this"},
    };
    info.defaults = CpdOptions{};
    info.create = [](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        return std::make_unique<CpdMethod>(ParseCpdOptions(j));
    };
    return info;
}

}  // namespace regbench
