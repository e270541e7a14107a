#include "runners/registry.hpp"

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
    return FindMethod(name).cost(params.is_null() ? nlohmann::json::object() : params);
}

std::map<std::string, std::string> PaperRowLabels() {
    std::map<std::string, std::string> out;
    for (const auto& m : AllMethods()) {
        if (!m.paper_label.empty()) out[m.name] = m.paper_label;
    }
    return out;
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
