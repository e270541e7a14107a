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

/// One method's cells beside the paper's (absent paper cells are nullopt).
struct PaperComparisonRow {
    std::string method;
    std::string paper_row;  ///< the paper's name for it, "" when the paper has none
    std::size_t pairs = 0;  ///< pairs our means are over
    double mae_r = 0.0, mae_t = 0.0, ccd = 0.0, median_seconds = 0.0;
    std::optional<double> paper_mae_r, paper_mae_t, paper_ccd, paper_seconds;
};

struct PaperComparison {
    std::string table, group, caption;
    std::vector<PaperComparisonRow> rows;
};

/// Our summaries beside the paper's cells of `table`, column group `group`. Throws
/// std::invalid_argument listing the valid tables / groups.
PaperComparison BuildPaperComparison(const std::vector<MethodSummary>& ours,
                                     const nlohmann::json& paper,
                                     const std::string& table,
                                     const std::string& group);

/// The comparison as `format`: md (a Markdown table), csv (one header line, one record per
/// method; absent paper cells empty), json, latex (booktabs tabular).
std::string FormatPaperComparison(const PaperComparison& comparison, const std::string& format);
nlohmann::json ToJson(const PaperComparison& comparison);

/// Markdown table: our pairs, mae_r / mae_t / ccd / time next to the paper's cells of `table`
/// restricted to the column group `group` (e.g. "same_category"; "" for tables without groups).
/// Throws std::invalid_argument listing the valid tables / groups.
std::string FormatPaperComparison(const std::vector<MethodSummary>& ours,
                                  const nlohmann::json& paper,
                                  const std::string& table,
                                  const std::string& group);

}  // namespace regbench
