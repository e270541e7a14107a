#pragma once
#include "core/registration.hpp"

namespace regbench {

/// `icp-pl`: Open3D point-to-plane ICP (RegistrationICP with
/// TransformationEstimationPointToPlane), started from the identity. Target normals come
/// from Open3D's EstimateNormals with a KDTreeSearchParamHybrid neighbourhood.
MethodInfo IcpPlMethodInfo();

}  // namespace regbench
