#include "baselines/identity.hpp"

#include "baselines/schemas.hpp"
#include "core/method_spec.hpp"

namespace regbench {
namespace {

AlignResult AlignIdentity(const NoOptions&,
                          const PointCloud&,
                          const PointCloud&,
                          const AlignContext&) {
    AlignResult r;
    r.stop_reason = "no_op";
    return r;
}

}  // namespace

MethodInfo IdentityMethodInfo() {
    return MakeMethodInfo(SpecOf<NoOptions>(BaselineSchema("identity")), AlignIdentity);
}

}  // namespace regbench
