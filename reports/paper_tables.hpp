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

/// What `report --paper TABLE[:GROUP]` names, resolved against the paper's tables.
struct PaperSelection {
    std::string table;  ///< a table id of the paper's file, e.g. "table1_modelnet_partial"
    std::string group;  ///< one of its column groups ("same_category"); "" for a table without
};

/// Resolves `text` = TABLE[:GROUP]: TABLE is a table id or, as `reproduce --tables` takes them,
/// a prefix of one ("table1"; a prefix of several, "supp", is refused naming them); GROUP is one
/// of that table's column groups, required where it has some and refused where it has none.
/// Throws std::invalid_argument naming `text` and listing the tables or groups; a table with no
/// MAE(R) or seconds column (the supplement's overlap-ratio and cluster-count sweeps) is refused
/// too, since its cells are not what the comparison shows.
PaperSelection ResolvePaperSelection(const nlohmann::json& paper, const std::string& text);

/// `--paper TABLE[:GROUP]`: our means of `ours` (pairs, mae_r, mae_t, ccd, median seconds)
/// beside the paper's cells of `table`, column group `group` ("" for tables without groups),
/// and the paper's seconds (Tab. 6). The caption names the paper's table, a note our data.
/// Throws std::invalid_argument listing the valid tables / groups.
Table PaperComparisonTable(const ReportTable& ours, const nlohmann::json& paper,
                           const std::string& table, const std::string& group,
                           const PaperRows& paper_rows);

}  // namespace regbench
