#pragma once
// The registry: one explicit list of every method regbench can run.
#include <memory>
#include <string>
#include <vector>

#include "core/registration.hpp"

namespace regbench {

/// Every registered method, in display order.
const std::vector<MethodInfo>& AllMethods();
/// Looks a method up by name; throws std::invalid_argument listing the known names.
const MethodInfo& FindMethod(const std::string& name);
/// How a method's time per iteration grows with the cloud sizes N (source) and M (target).
enum class CostClass {
    kConstant,    ///< independent of the clouds (identity)
    kNearLinear,  ///< O((N + M) log M): kd-tree, voxel or lattice based
    kQuadratic,   ///< O(N * M): dense kernel sums over all point pairs
};

/// The cost class each registered method declares (listed next to AllMethods in registry.cpp)
/// with its resolved `params`: CPD with `e_step` auto or truncated and GMMReg / SVR with
/// `kernel_sums` auto switch to their approximations (cell compression, truncation, kd-tree
/// cutoff; SVR also fits its SVMs on at most `svm_max_points` points) at scale and are
/// kNearLinear; their dense modes (`e_step` / `kernel_sums` "dense") are kQuadratic, as is
/// a method without a declared class. Throws std::invalid_argument for an unknown name.
CostClass MethodCost(const std::string& name, const nlohmann::json& params = {});

/// FindMethod(name).create(params).
std::unique_ptr<RegistrationMethod> CreateMethod(const std::string& name,
                                                 const nlohmann::json& params = {});

}  // namespace regbench
