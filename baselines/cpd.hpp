#pragma once
// Rigid Coherent Point Drift (Myronenko & Song, TPAMI 2010) as probreg 0.3.7 implements it,
// with its two deviations from the paper made explicit options (spec:
// ../shared/specs/probabilistic-baselines.md section 1).
#include <nlohmann/json.hpp>
#include <string>

#include "core/registration.hpp"

namespace regbench {

/// Options of `cpd`. `compat` picks the defaults of update_scale and sigma2_formula; a value
/// given explicitly always wins over the compat preset:
///   compat "none"    -> update_scale false, sigma2_formula "ml": the correct rigid algorithm;
///   compat "probreg" -> update_scale true,  sigma2_formula "probreg": registration_cpd(...,
///                       'rigid') as published (similarity transform; with update_scale false
///                       its sigma^2 = (cx + b - a)/(Np D) bug, which stalls sigma^2).
struct CpdOptions {
    double w = 0.0;                     ///< outlier weight of the uniform component, in [0, 1)
    int maxiter = 50;                   ///< EM iterations, >= 1 (probreg 50, MATLAB 150)
    double tol = 1e-3;                  ///< stop when |q - q_prev| < tol (absolute), >= 0
    bool update_scale = false;          ///< estimate s (similarity); default from compat
    std::string sigma2_formula = "ml";  ///< "ml" or "probreg"; default from compat
    double sigma2 = 0.0;                ///< initial sigma^2 (> 0), or 0 = sqsum(Y, X)
    std::string compat = "none";        ///< "none" or "probreg" (see above)
    std::string e_step = "auto";        ///< "auto", "dense" or "truncated" (core/gauss_sum.hpp)
    double truncation_sigmas = 4.0;     ///< truncated E-step radius r = k sigma, > 0
    int truncation_min_points = 20000;  ///< auto: truncate only when max(M, N) >= this
    /// auto: cell edge (in sigmas) of the cell-compressed E-step at scale; 0 = never compress
    double cluster_cell_sigmas = 0.25;
    int cluster_min_points = 20000;  ///< auto: compress only when max(M, N) >= this
};

/// Parses and validates CPD options, applying the compat preset to keys absent from `j`.
/// Throws std::invalid_argument naming the offending parameter.
CpdOptions ParseCpdOptions(const nlohmann::json& j);

/// `cpd`: rigid (optionally similarity) CPD, fused float E-step with exact double M-step.
MethodInfo CpdMethodInfo();

}  // namespace regbench
