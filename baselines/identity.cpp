#include "baselines/identity.hpp"

#include "core/params.hpp"

namespace regbench {
namespace {

AlignResult AlignIdentity(const NoOptions&, const PointCloud&, const PointCloud&,
                          const AlignContext&) {
    AlignResult r;
    r.stop_reason = "no_op";
    return r;
}

}  // namespace

MethodInfo IdentityMethodInfo() {
    return MakeMethodInfo<NoOptions>(
        "identity", "no motion (returns I); the floor every method must beat", AlignIdentity);
}

}  // namespace regbench
