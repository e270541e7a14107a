#pragma once
#include "core/registration.hpp"

namespace regbench {

/// `icp`: Open3D point-to-point ICP (RegistrationICP), started from the identity, with the
/// OGMM code's settings (lib/o3dutils.py).
MethodInfo IcpMethodInfo();

}  // namespace regbench
