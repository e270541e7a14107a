#include "runners/registry.hpp"

#include <map>
#include <stdexcept>
#include <utility>

#include "baselines/cpd.hpp"
#include "baselines/fgr.hpp"
#include "baselines/filterreg.hpp"
#include "baselines/gicp.hpp"
#include "baselines/gmmreg.hpp"
#include "baselines/icp.hpp"
#include "baselines/icp_pl.hpp"
#include "baselines/identity.hpp"
#include "baselines/ndt.hpp"
#ifdef REGBENCH_HAVE_LEARNED
#include "baselines/learned.hpp"
#endif
#include "baselines/svr.hpp"
#include "core/suggest.hpp"

namespace regbench {

const std::vector<MethodInfo>& AllMethods() {
    static const std::vector<MethodInfo> methods = [] {
        std::vector<MethodInfo> m = {IdentityMethodInfo(), IcpMethodInfo(),    IcpPlMethodInfo(),
                                     FgrMethodInfo(),      GicpMethodInfo(),   NdtMethodInfo(),
                                     CpdMethodInfo(),      GmmRegMethodInfo(), SvrMethodInfo(),
                                     FilterRegMethodInfo()};
#ifdef REGBENCH_HAVE_LEARNED
        for (auto& info : LearnedMethodInfos()) m.push_back(std::move(info));
#endif
        return m;
    }();
    return methods;
}

CostClass MethodCost(const std::string& name, const nlohmann::json& params) {
    // CPD's E-step and GMMReg's Gauss transform sum a kernel over every (source, target) point
    // pair; SVR trains a one-class SVM whose kernel matrix is quadratic in the points. The rest
    // search kd-trees (ICP, GICP, FGR), voxel grids (NDT) or a permutohedral lattice
    // (FilterReg). The numbers behind this: README "Larger clouds".
    static const std::map<std::string, CostClass> kCost = {
        {"identity", CostClass::kConstant}, {"icp", CostClass::kNearLinear},
        {"icp-pl", CostClass::kNearLinear}, {"fgr", CostClass::kNearLinear},
        {"gicp", CostClass::kNearLinear},   {"ndt", CostClass::kNearLinear},
        {"cpd", CostClass::kQuadratic},     {"gmmreg", CostClass::kQuadratic},
        {"svr", CostClass::kQuadratic},     {"filterreg", CostClass::kNearLinear},
    };
    FindMethod(name);  // unknown names fail with the list of known ones
    // The approximations switch on by themselves above their size thresholds (defaults:
    // gmm/gauss_sum.hpp GaussSumOptions, gmm/gmm_l2.hpp L2SumOptions); only the dense modes
    // keep the O(N*M) cost at every size.
    const auto mode = [&](const char* key) {
        return params.is_object() && params.contains(key) && params[key].is_string()
                   ? params[key].get<std::string>()
                   : std::string("auto");
    };
    if (name == "cpd")
        return mode("e_step") == "dense" ? CostClass::kQuadratic : CostClass::kNearLinear;
    if (name == "gmmreg" || name == "svr") {
        return mode("kernel_sums") == "dense" ? CostClass::kQuadratic : CostClass::kNearLinear;
    }
    const auto it = kCost.find(name);
    // A method added to AllMethods without a declared class is treated as the expensive kind.
    return it == kCost.end() ? CostClass::kQuadratic : it->second;
}

const MethodInfo& FindMethod(const std::string& name) {
    for (const auto& m : AllMethods()) {
        if (m.name == name) return m;
    }
    std::string known;
    std::vector<std::string> names;
    for (const auto& m : AllMethods()) {
        known += (known.empty() ? "" : ", ") + m.name;
        names.push_back(m.name);
    }
    throw std::invalid_argument("unknown method '" + name + "' (" + DidYouMean(name, names) +
                                "known: " + known + ")");
}

std::unique_ptr<RegistrationMethod> CreateMethod(const std::string& name,
                                                 const nlohmann::json& params) {
    return FindMethod(name).create(params.is_null() ? nlohmann::json::object() : params);
}

}  // namespace regbench
