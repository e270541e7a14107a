#pragma once
// The OGMM paper's published numbers (data/paper/ogmm_wacv2023_tables.json) next to ours.
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "reports/report.hpp"

namespace regbench {

/// Loads the paper's tables; throws naming the path when missing or malformed.
nlohmann::json LoadPaperTables(const std::string& path);

/// Default location: DataDir()/paper/ogmm_wacv2023_tables.json (core/data_dir.hpp).
std::string DefaultPaperTablesPath();

/// The paper's row name for a regbench method name (icp -> ICP, cpd -> CPD, ...), if any.
std::optional<std::string> PaperRowName(const std::string& method);

/// Markdown table: our mae_r / mae_t / ccd / time next to the paper's cells of `table`
/// restricted to the column group `group` (e.g. "same_category"; "" for tables without groups).
/// Throws std::invalid_argument listing the valid tables / groups.
std::string FormatPaperComparison(const std::vector<MethodSummary>& ours,
                                  const nlohmann::json& paper,
                                  const std::string& table,
                                  const std::string& group);

}  // namespace regbench
