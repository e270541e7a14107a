#pragma once
#include "core/registration.hpp"

namespace regbench {

/// `ndt`: 3-D Normal Distributions Transform (Magnusson 2009) as PCL implements it
/// (pcl::NormalDistributionsTransform, float32, More-Thuente line search), from the identity.
/// The target is voxelised into Gaussians; the source points are registered to them.
MethodInfo NdtMethodInfo();

}  // namespace regbench
