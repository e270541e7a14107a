#pragma once
#include "core/registration.hpp"

namespace regbench {

/// `identity`: returns no motion. The floor every method must beat.
MethodInfo IdentityMethodInfo();

}  // namespace regbench
