#pragma once
#include "core/registration.hpp"

namespace regbench {

/// `gmmreg`: rigid GMMReg as probreg's registration_gmmreg runs it (spherical sklearn-style
/// GMM features, L2 cost, scipy-like BFGS); probabilistic-baselines.md Sec. 2.
MethodInfo GmmRegMethodInfo();

}  // namespace regbench
