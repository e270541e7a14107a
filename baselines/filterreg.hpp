#pragma once
// FilterReg (Gao & Tedrake, "FilterReg: Robust and Efficient Probabilistic Point-Set
// Registration using Gaussian Filter and Twist Parameterization", CVPR 2019), rigid, as
// probreg 0.3.x runs it (`registration_filterreg`): an E-step that filters the target through
// a permutohedral lattice built over [T(Y)/sigma; X/sigma] and a weighted Kabsch (pt2pt) or
// twist Gauss-Newton (pt2pl) M-step. See docs/probabilistic-baselines.md ("FilterReg") for what
// matches probreg and what does not.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

#include "core/method_spec.hpp"
#include "core/point_cloud.hpp"
#include "core/registration.hpp"

namespace regbench {

/// FilterReg's M-step objective.
enum class FilterRegObjective {
    kPt2Pt,  ///< weighted Kabsch to the filtered target mean
    kPt2Pl,  ///< twist Gauss-Newton on filtered target normals
};
NLOHMANN_JSON_SERIALIZE_ENUM(FilterRegObjective,
                             {{FilterRegObjective::kPt2Pt, "pt2pt"},
                              {FilterRegObjective::kPt2Pl, "pt2pl"}})

/// How the E-step evaluates the Gaussian filter.
enum class FilterRegEstimator {
    kLattice,  ///< permutohedral lattice (probreg)
    kExact,    ///< Gaussian sums within 3 sigma
};
NLOHMANN_JSON_SERIALIZE_ENUM(FilterRegEstimator,
                             {{FilterRegEstimator::kLattice, "lattice"},
                              {FilterRegEstimator::kExact, "exact"}})

/// Options of `filterreg`, documented in baselines/filterreg.schema.json with their defaults
/// (probreg's `registration_filterreg` ones, except that compat "probreg" switches
/// update_sigma2 off unless it is given) and ranges.
struct FilterRegOptions {
    double sigma2;
    bool update_sigma2;
    double w;
    int maxiter;
    double tol;
    double min_sigma2;
    FilterRegObjective objective;
    FilterRegEstimator estimator;
    Compat compat;
    int normals_k;
};
// clang-format off
REGBENCH_OPTION_FIELDS(FilterRegOptions, sigma2, update_sigma2, w, maxiter, tol, min_sigma2,
                       objective, estimator, compat, normals_k)
// clang-format on

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
                                FilterRegEstimator estimator = FilterRegEstimator::kLattice,
                                LatticeBlur blur = LatticeBlur::kAuto);

/// `filterreg`: registry entry (name, summary, param_docs, defaults, create).
MethodInfo FilterRegMethodInfo();

}  // namespace regbench
