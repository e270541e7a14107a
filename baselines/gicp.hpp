#pragma once
#include "core/registration.hpp"

namespace regbench {

/// `gicp`: Generalized-ICP (Segal et al., RSS 2009) as PCL implements it
/// (pcl::GeneralizedIterativeClosestPoint, float32, BFGS inner solver), from the identity.
MethodInfo GicpMethodInfo();

}  // namespace regbench
