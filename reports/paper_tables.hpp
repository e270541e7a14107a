#pragma once
// The OGMM paper's published numbers (data/paper/ogmm_wacv2023_tables.json) next to ours.
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "reports/report.hpp"
#include "reports/table.hpp"

namespace regbench {

/// Loads the paper's tables; throws naming the path when missing or malformed.
nlohmann::json LoadPaperTables(const std::string& path);

/// Default location: DataDir()/paper/ogmm_wacv2023_tables.json (core/data_dir.hpp).
std::string DefaultPaperTablesPath();

/// regbench method name -> the row of the OGMM paper's tables it fills (icp -> ICP, ...): each
/// method declares its own (MethodInfo::paper_label; runners/registry.hpp PaperRows() collects
/// them), so the reports name no method.
using PaperRows = std::map<std::string, std::string>;

/// The paper's row name for a regbench method name, if `rows` has one.
std::optional<std::string> PaperRowName(const PaperRows& rows, const std::string& method);

/// `--paper TABLE[:GROUP]`: our means of `ours` (pairs, mae_r, mae_t, ccd, median seconds)
/// beside the paper's cells of `table`, column group `group` ("" for tables without groups),
/// and the paper's seconds (Tab. 6). The caption names the paper's table, a note our data.
/// Throws std::invalid_argument listing the valid tables / groups.
Table PaperComparisonTable(const ReportTable& ours, const nlohmann::json& paper,
                           const std::string& table, const std::string& group,
                           const PaperRows& paper_rows);

}  // namespace regbench
