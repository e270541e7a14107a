#pragma once
// The paper's tables (Tab. 1-6 and the supplementary ones) rebuilt from regbench result rows,
// every measured cell beside the published one.
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "reports/paper_tables.hpp"
#include "reports/statistics.hpp"
#include "reports/table.hpp"
#include "runners/result_row.hpp"

namespace regbench {

/// One column group of a paper table and the result rows measured for it.
struct ResultSet {
    std::string group;  ///< e.g. "same_category", "jitter", "30%", "" for ungrouped tables
    std::vector<ResultRow> rows;
    Provenance provenance;
    /// For ablation / sweep tables: every row of this set fills the paper row of this name
    /// (e.g. "no_SPE"); empty = each row fills the row of its method.
    std::string row_label;
};

/// Static description of a paper table: its column groups and metrics.
struct PaperTableSpec {
    std::string id;     ///< key in the paper JSON, e.g. "table1_modelnet_partial"
    std::string title;  ///< e.g. "Tab. 1: partial-to-partial registration (ModelNet40)"
    std::vector<std::string> groups;   ///< column groups ("" when the table has none)
    std::vector<std::string> metrics;  ///< per group
    bool rows_are_methods = true;      ///< false: ablation variants (rows from ResultSet labels)
    std::string paper_data;            ///< what the paper measured on, e.g. "ModelNet40"
    /// Groups regbench adds beside the paper's, and the paper group their paper column shows
    /// (e.g. "c2c_clean" -> "c2c": the noise-free shared-sample variant of the noisy c2c).
    std::map<std::string, std::string> paper_group_of = {};
    /// First sentence of the caption; "" = the paper's. A table the paper lacks (an
    /// experiment file of a user) has no paper columns.
    std::string caption = {};
};

/// The paper group whose published cells sit beside group `g` of `spec` (g itself unless
/// spec.paper_group_of maps it).
std::string PaperGroupOf(const PaperTableSpec& spec, const std::string& g);

/// Every table of the paper this module knows, in the paper's order.
const std::vector<PaperTableSpec>& PaperTableSpecs();

/// The spec of `id`; throws std::invalid_argument listing the known ids.
const PaperTableSpec& FindPaperTableSpec(const std::string& id);

/// The paper's cell (row as the paper names it, e.g. "CPD"; group and metric as in the spec),
/// handling the supplementary tables whose rows are metrics; NaN when the paper has none.
double PaperCell(const nlohmann::json& paper, const std::string& table,
                 const std::string& paper_row, const std::string& group, const std::string& metric);

/// Options for building a paper table.
struct PaperTableOptions {
    int bootstrap_samples = 1000;  ///< CIs of the measured means
    std::uint64_t seed = kDefaultBootstrapSeed;
    /// Methods (regbench names) that could not run, with the reason shown in their cells
    /// (e.g. {"ogmm", "not trained"}).
    std::map<std::string, std::string> unavailable;
    /// The paper's row name of each method (reports/paper_tables.hpp PaperRows); a method
    /// without one fills a row of its own name.
    PaperRows paper_rows;
};

/// Builds the table: the paper's rows in its order (plus measured methods the paper lacks),
/// for every group and metric a measured column (mean ± 95% CI half-width) and the paper's.
/// The caption names each side's data and the pairing; the notes give each group's
/// ground-truth CCD floor and any dataset fallback.
Table BuildPaperTable(const PaperTableSpec& spec, const std::vector<ResultSet>& sets,
                      const nlohmann::json& paper, const PaperTableOptions& options);

/// Tab. 6: mean / median CPU ms per call measured (one thread per call), and for the learned
/// methods the network's CPU ms, its GMAC, floor ms and x floor (from the rows' extra
/// network_cpu_seconds, macs, floor_seconds; blank for the classical methods), points per
/// cloud, threads, beside the paper's ms (their GPU / CPU). A set with a row_label fills a row
/// of that name (e.g. "OGMM_full_attention", the paper's row). The caption names the CPU
/// model, `blas` (the classical methods'), the learned rows' BLAS and GEMM rate.
Table BuildTimingTable(const std::vector<ResultSet>& sets, const nlohmann::json& paper,
                       const std::string& cpu_model, const std::string& blas,
                       const PaperRows& paper_rows);

}  // namespace regbench
