#include "baselines/identity.hpp"

#include "core/params.hpp"

namespace regbench {
namespace {

/// No parameters; its cost does not depend on the clouds.
struct IdentityOptions : NoOptions {
    CostClass Cost() const { return CostClass::kConstant; }
};

AlignResult AlignIdentity(const IdentityOptions&, const PointCloud&, const PointCloud&,
                          const AlignContext&) {
    AlignResult r;
    r.stop_reason = "no_op";
    return r;
}

}  // namespace

MethodInfo IdentityMethodInfo() {
    return MakeMethodInfo<IdentityOptions>(
        "identity", "no motion (returns I); the floor every method must beat", AlignIdentity);
}

}  // namespace regbench
