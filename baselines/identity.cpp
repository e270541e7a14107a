#include "baselines/identity.hpp"

#include "core/method_spec.hpp"

namespace regbench {
namespace {

struct IdentityOptions {};

const MethodSpec<IdentityOptions>& Spec() {
    static const MethodSpec<IdentityOptions> spec{
        "identity", "no motion (returns I); the floor every method must beat", {}, nullptr, {}};
    return spec;
}

AlignResult AlignIdentity(const IdentityOptions&,
                          const PointCloud&,
                          const PointCloud&,
                          const AlignContext&) {
    AlignResult r;
    r.stop_reason = "no_op";
    return r;
}

}  // namespace

MethodInfo IdentityMethodInfo() { return MakeMethodInfo(Spec(), AlignIdentity); }

}  // namespace regbench
