#pragma once
// The registry: one explicit list of every method regbench can run.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/registration.hpp"

namespace regbench {

/// Every registered method, in display order.
const std::vector<MethodInfo>& AllMethods();
/// Looks a method up by name; throws std::invalid_argument listing the known names.
const MethodInfo& FindMethod(const std::string& name);
/// The cost class method `name` declares (MethodInfo::cost, from its options' Cost()) under
/// its resolved `params`. Throws std::invalid_argument for an unknown name.
CostClass MethodCost(const std::string& name, const nlohmann::json& params = {});

/// Method name -> the row of the OGMM paper's tables it fills (MethodInfo::paper_label), for
/// every registered method that has one (reports/paper_tables.hpp PaperRows).
std::map<std::string, std::string> PaperRowLabels();

/// FindMethod(name).create(params).
std::unique_ptr<RegistrationMethod> CreateMethod(const std::string& name,
                                                 const nlohmann::json& params = {});

}  // namespace regbench
