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

#include "core/params.hpp"
#include "core/point_cloud.hpp"
#include "core/registration.hpp"
#include "gmm/gmm_common.hpp"

namespace regbench {

/// FilterReg's M-step objective.
enum class FilterRegObjective {
    kPt2Pt,  ///< weighted Kabsch to the filtered target mean
    kPt2Pl,  ///< twist Gauss-Newton on filtered target normals
};
REGBENCH_CHOICES(FilterRegObjective,
                 {{FilterRegObjective::kPt2Pt, "pt2pt"}, {FilterRegObjective::kPt2Pl, "pt2pl"}})

/// How the E-step evaluates the Gaussian filter.
enum class FilterRegEstimator {
    kLattice,  ///< permutohedral lattice (probreg)
    kExact,    ///< Gaussian sums within 3 sigma
};
REGBENCH_CHOICES(FilterRegEstimator,
                 {{FilterRegEstimator::kLattice, "lattice"}, {FilterRegEstimator::kExact, "exact"}})

/// Options of `filterreg`: probreg's `registration_filterreg` defaults, except that compat
/// "probreg" switches update_sigma2 off unless it is given.
/// sigma2 (the initial kernel variance [length^2]), w, maxiter and tol (checked from the 2nd
/// iteration) are the GmmEmOptions base (gmm/gmm_common.hpp).
struct FilterRegOptions : GmmEmOptions {
    bool update_sigma2 = true;  ///< re-estimate sigma2 in every M-step
    /// floor on sigma2 after each iteration and on the auto init
    double min_sigma2 = 0.0001;
    FilterRegObjective objective = FilterRegObjective::kPt2Pt;    ///< "pt2pt" or "pt2pl"
    FilterRegEstimator estimator = FilterRegEstimator::kLattice;  ///< "lattice" or "exact"
    Compat compat = Compat::kNone;                                ///< "none" or "probreg"
    int normals_k = 30;  ///< pt2pl only: neighbours for the target's PCA normals

    template <class F>
    void Fields(F&& f) {
        f("sigma2", sigma2,
          "initial kernel variance [length^2]; 0 or null = max(sqsum(Y,X), min_sigma2) (probreg)",
          Nullable::kYes);
        f("update_sigma2", update_sigma2,
          "re-estimate sigma2 in every M-step; default true; false under compat = \"probreg\" "
          "unless given (probreg keeps sigma fixed)");
        f("w", w, "weight of the uniform outlier component; probreg default 0");
        f("maxiter", maxiter, "maximum EM iterations; probreg default 50");
        f("tol", tol,
          "stop when |q - q_prev| < tol (absolute), checked from the 2nd iteration; 1e-3");
        f("min_sigma2", min_sigma2,
          "floor on sigma2 after each iteration and on the auto init [unit-sphere units^2]; "
          "1e-4");
        f("objective", objective,
          "\"pt2pt\" (Kabsch to the filtered target mean) or \"pt2pl\" (twist Gauss-Newton on "
          "filtered target normals, normals by PCA of normals_k neighbours; give a small sigma2, "
          "e.g. 0.01 as probreg's example: from sqsum its undamped steps can flip the cloud)");
        f("estimator", estimator,
          "\"lattice\": permutohedral lattice, blurred only while <= 0.015 N vertices (probreg); "
          "\"exact\": Gaussian sums within 3 sigma (kd-tree), not probreg-equivalent");
        f("compat", compat,
          "\"none\" (default): consistent w_i^2 weights and update_sigma2 on unless given; "
          "\"probreg\": Kabsch centroids weighted by w_i but H by w_i^2, pt2pl weighted by w_i, "
          "sigma fixed");
        f("normals_k", normals_k, "pt2pl only: neighbours for the target's PCA normals; 30");
    }
    void Validate(ParamCheck& c) const {
        GmmEmOptions::Validate(c);
        c.Finite("min_sigma2", min_sigma2);
        c.Above("min_sigma2", min_sigma2, 0.0);
        c.AtLeast("normals_k", normals_k, 3);
    }
    /// Scale guard class: permutohedral lattice, near-linear.
    CostClass Cost() const { return CostClass::kNearLinear; }
    /// compat "probreg": probreg 0.3.7's defaults for these keys.
    void ApplyCompat() {
        if (compat != Compat::kProbreg) return;
        update_sigma2 = false;
    }
};

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
FilterRegMoments FilterRegEStep(const PointCloud& moved_source, const PointCloud& target,
                                const Normals* target_normals, double sigma2, bool with_m2,
                                FilterRegEstimator estimator = FilterRegEstimator::kLattice,
                                LatticeBlur blur = LatticeBlur::kAuto);

/// `filterreg`: registry entry (name, summary, param_docs, defaults, create).
MethodInfo FilterRegMethodInfo();

}  // namespace regbench
