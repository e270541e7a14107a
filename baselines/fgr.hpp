#pragma once
#include "core/registration.hpp"

namespace regbench {

/// `fgr`: Fast Global Registration (Zhou et al., ECCV 2016) as Open3D implements it:
/// FPFH features (ComputeFPFHFeature) matched by FastGlobalRegistrationBasedOnFeatureMatching,
/// with the Open3D tutorial's voxel-based radii. Seeds Open3D's process-global RNG (used for
/// the tuple test) right before each call, so concurrent `fgr` calls in one process are not
/// reproducible; run one per process or serialise them.
MethodInfo FgrMethodInfo();

}  // namespace regbench
