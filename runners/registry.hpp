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
/// FindMethod(name).create(params).
std::unique_ptr<RegistrationMethod> CreateMethod(const std::string& name,
                                                 const nlohmann::json& params = {});

}  // namespace regbench
