#pragma once
// FilterReg (Gao & Tedrake, "FilterReg: Robust and Efficient Probabilistic Point-Set
// Registration using Gaussian Filter and Twist Parameterization", CVPR 2019), rigid, as
// probreg 0.3.x runs it (`registration_filterreg`): an E-step that filters the target through
// a permutohedral lattice built over [T(Y)/sigma; X/sigma] and a weighted Kabsch (pt2pt) or
// twist Gauss-Newton (pt2pl) M-step. See docs/probabilistic-baselines.md ("FilterReg") for
// what matches probreg and what does not.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

#include "core/point_cloud.hpp"
#include "core/registration.hpp"

namespace regbench {

/// Options of `filterreg`. Defaults are probreg's `registration_filterreg` defaults, except
/// that compat "probreg" switches update_sigma2 off unless it is given (see FilterRegMethodInfo).
struct FilterRegOptions {
    double sigma2 = 0.0;  ///< initial variance [length^2]; 0 = auto: max(sqsum(Y,X), min_sigma2)
    bool update_sigma2 = true;  ///< re-estimate sigma2 each M-step (probreg: false, sigma fixed)
    double w = 0.0;              ///< outlier weight of the uniform component, in [0, 1)
    int maxiter = 50;            ///< maximum EM iterations, >= 1
    double tol = 1e-3;           ///< stop when |q - q_prev| < tol (absolute), from iteration 2
    double min_sigma2 = 1e-4;    ///< floor on sigma2 [length^2], > 0
    std::string objective = "pt2pt";    ///< "pt2pt" (Kabsch) or "pt2pl" (twist, target normals)
    std::string estimator = "lattice";  ///< "lattice" (probreg) or "exact" (3-sigma Gaussian sums)
    std::string compat = "none";  ///< "none" (consistent, default) or "probreg" (w / w^2 Kabsch)
    int normals_k = 30;           ///< pt2pl only: neighbours for the target's PCA normals, >= 3
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(FilterRegOptions,
                                                sigma2,
                                                update_sigma2,
                                                w,
                                                maxiter,
                                                tol,
                                                min_sigma2,
                                                objective,
                                                estimator,
                                                compat,
                                                normals_k)

/// Parses and validates `filterreg` parameters: unknown keys, wrong types and out-of-range
/// values throw std::invalid_argument naming the parameter. Applies the compat "none"
/// default (update_sigma2 = true unless given).
FilterRegOptions ParseFilterRegOptions(const nlohmann::json& params);

/// How the lattice E-step chooses the blur.
enum class LatticeBlur {
    kAuto,  ///< probreg: blur unless the blurred lattice has > 0.015 N vertices
    kOn,    ///< always blur (diagnostics)
    kOff,   ///< never blur
};

/// Filtered target moments at each (moved) source point y_i, with kernel k_ij:
/// m0_i = sum_j k_ij, m1_i = sum_j k_ij x_j, m2_i = sum_j k_ij |x_j|^2, nx_i = sum_j k_ij n_j.
struct FilterRegMoments {
    Eigen::VectorXd m0;
    PointCloud m1;
    Eigen::VectorXd m2;        ///< empty unless requested
    PointCloud nx;             ///< empty unless normals were given
    bool blurred = false;      ///< lattice only: the blurred lattice was used
    int lattice_vertices = 0;  ///< lattice only: vertices of the blurred lattice when used, else 0
};

/// One E-step on its own (tests, diagnostics). `target_normals` may be null. The lattice
/// estimator builds over [moved_source/sigma; target/sigma] as probreg; "exact" sums
/// k_ij = exp(-|y_i - x_j|^2 / 2 sigma2) over |y_i - x_j| <= 3 sigma.
FilterRegMoments FilterRegEStep(const PointCloud& moved_source,
                                const PointCloud& target,
                                const Normals* target_normals,
                                double sigma2,
                                bool with_m2,
                                const std::string& estimator = "lattice",
                                LatticeBlur blur = LatticeBlur::kAuto);

/// `filterreg`: registry entry (name, summary, param_docs, defaults, create).
MethodInfo FilterRegMethodInfo();

}  // namespace regbench
