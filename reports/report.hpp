#pragma once
// Aggregates result rows into per-method summaries (ReportTable: rows of MethodSummary, notes)
// and those into report tables (reports/table.hpp), which the table writers render.
// Metrics, thresholds and success rules are defined in docs/metrics.md.
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "reports/conventions.hpp"
#include "reports/statistics.hpp"
#include "reports/table.hpp"
#include "runners/result_row.hpp"

namespace regbench {

/// 3DMatch-style registration recall: RMSE of the ground-truth-overlapping source points under
/// the estimate below kRecall3dmatchRmse, with rre < kRecall3dmatchRreDeg and rte below
/// kRecall3dmatchRte.
constexpr double kRecall3dmatchRmse = 0.2;
constexpr double kRecall3dmatchRreDeg = 15.0;
constexpr double kRecall3dmatchRte = 0.3;

struct ReportOptions {
    double recall_r_deg = 1.0;     ///< recall@(r, t): mae_r < r [deg] and mae_t < t (paper code)
    double recall_t = 0.1;         ///< recall@(r, t): mae_t threshold
    double success_rre_deg = 5.0;  ///< success: rre < this [deg] and rte < success_rte
    double success_rte = 0.1;      ///< success: rte threshold
    /// `--recall-t` / `--success-rte` given: used as is. A threshold not given is in unit-sphere
    /// units, and ForData multiplies it by the table's pair-file scale (DataTag::scale), as it
    /// does the distance bounds of the success presets and of the 3DMatch-style recall.
    bool recall_t_given = false;
    bool success_rte_given = false;
    /// The factor ForData multiplied the distance defaults by (1: none; the caption says so).
    double distance_scale = 1.0;
    int bootstrap_samples = 1000;  ///< BootstrapMean resamples of the means' 95% CIs
    bool recall_3dmatch = false;   ///< add the 3DMatch-style recall column
    /// Convention of mae_r / rmse_r to report. Unset: each row's own (tables never mix two).
    /// Set: rows in another convention are recomputed from their stored ground truth, or
    /// refused when they carry none (rows written before `gt_transform` existed).
    std::optional<EulerConvention> euler;
    /// Methods of one table measured on different pairs of its pair file (a shard, a partial
    /// run) are refused by BuildTables, naming them; with this set, every method of such a
    /// table is restricted to the pairs all of them have, and the caption says so.
    bool common_pairs = false;
    /// The success column's rule: "rre-rte" (success_rre_deg / success_rte) or a preset of
    /// reports/conventions.hpp (kitti, 3dmatch-rmse, ...).
    std::string success_rule = "rre-rte";
    /// Pairs the rre / rte means average over: all with finite metrics, or the successful ones.
    ErrorPairs rre_rte_over = ErrorPairs::kAll;
    /// Rates (recall, success, 3DMatch recall) per pair, or the mean of per-scene rates.
    RatePer rates_per = RatePer::kPair;
};

/// `o` for a table of the pair file `data`: the distance thresholds not given (recall_t,
/// success_rte, the presets' and the 3DMatch recall's distances) in the pair file's units, i.e.
/// their unit-sphere values times data.scale (`generate --scale`; issue 54 item 1). Applying it
/// again, for this or another table, starts from the unit-sphere values.
ReportOptions ForData(const ReportOptions& o, const DataTag& data);

/// The success rule `o` names, at `o`'s distance scale (FindSuccessRule).
SuccessRule SuccessRuleOf(const ReportOptions& o);

/// Mean with its 95% bootstrap confidence interval (BootstrapMean, reports/statistics.hpp).
using Estimate = BootstrapCi;

/// One table row: one method with one parameter set over all its pairs.
struct MethodSummary {
    std::string method;
    std::string label;  ///< method, plus its params when one table holds several sets of them
    nlohmann::json params = nlohmann::json::object();
    std::size_t pairs = 0;
    std::size_t failed = 0;  ///< status != ok or a null metric (such rows count as not recalled)
    /// Why the first failed call (by pair) failed: "pair k: <status>: <message>"; "" if none.
    std::string first_failure;
    /// Means over the pairs with finite metrics, each with its bootstrap CI.
    Estimate mae_r, mae_t, ccd, rre, rte, chamfer;
    /// sqrt of the mean mse_r / mse_t; the CI is the square root of the mean's bootstrap CI.
    Estimate rmse_r, rmse_t;
    /// Rates over all pairs (failures count as misses), each with its Wilson interval.
    Estimate recall;          ///< recall@(recall_r_deg, recall_t)
    Estimate success;         ///< rre/rte based
    Estimate recall_3dmatch;  ///< 3DMatch-style (only with ReportOptions::recall_3dmatch)
    double median_seconds = 0.0;
    Estimate mean_seconds;  ///< seconds per call over all pairs, with its bootstrap CI
    /// Wall and CPU seconds per call over all pairs: 95th percentiles and the CPU median
    /// (SampleQuantile, numpy's linear definition). CPU NaN when no row recorded CPU time
    /// (every cpu_seconds 0 while some wall time is not: rows from before it existed, `score`).
    double p95_seconds = 0.0, median_cpu_seconds = 0.0, p95_cpu_seconds = 0.0;
    std::size_t successful = 0;  ///< pairs the success rule accepts (rre/rte over successful)
    std::size_t rate_groups = 0;  ///< scenes or categories the rates averaged over (pairs: n)
    int threads = 1;
    double ccd_clip = kCcdClip;     ///< the clip every row's ccd was measured with
    double inlier_threshold = 0.0;  ///< > 0: the rows carry Open3D's fitness / inlier RMSE
    double fitness = std::nan(""), inlier_rmse = std::nan("");  ///< their means
};

/// Rows computed on one pair file (same content) with one Euler convention.
struct ReportTable {
    DataTag data;
    EulerConvention euler = EulerConvention::kZyx;
    std::vector<std::string> files;      ///< result files the rows came from
    std::vector<MethodSummary> methods;  ///< in first-seen order
    std::vector<std::string> notes;      ///< "file:line: ..." for rows counted as failed
    /// Empty, or (with ReportOptions::common_pairs) how the table was restricted to the pairs
    /// every method has, e.g. "restricted to the 10 pairs every method has (icp: 30 -> 10)".
    std::string subset;
    /// The rows behind the table (after any common-pairs restriction), pointing into the
    /// vector given to BuildTables: valid while it lives. For the breakdowns of `report`.
    std::vector<const ResultRow*> rows;
    /// Threads, CPU model and library versions the rows record (DescribeEnvironment).
    std::string environment;
};

/// Groups rows by pair file (content hash; file name and provenance for old rows without
/// one) and Euler convention, and by (method, params) inside a group. Throws
/// std::runtime_error naming both file:line for a duplicated (pair, method, params) row, and
/// naming the methods and their pair counts when the methods of one group were measured on
/// different pairs (unless options.common_pairs: then restricted to the common pairs).
std::vector<ReportTable> BuildTables(const std::vector<ResultRow>& rows,
                                     const ReportOptions& options);

/// Summaries of rows that belong to one table (no grouping by data), in first-seen order.
std::vector<MethodSummary> Summarize(const std::vector<ResultRow>& rows,
                                     const ReportOptions& options);

/// One line describing a table's data and convention, e.g. for captions.
std::string DescribeTable(const ReportTable& table);

/// One caption line naming the conventions a summary table used: the pairs rre/rte average
/// over, what rates average over (with the number of scenes), the success and recall rules
/// with where they come from (docs/metrics.md, "Conventions").
std::string DescribeConventions(const ReportTable& table, const ReportOptions& o);

/// A ReportTable as a report table (reports/table.hpp): caption "Data: " + DescribeTable, a row
/// per (method, params), the means with their CIs, recall, success and seconds; chamfer, threads
/// and params as data columns (CSV and JSON only); the rows counted as failed as a note.
Table SummaryTable(const ReportTable& table, const ReportOptions& o);

/// SummaryTable of each, captions numbered "Table i of n. " when there are several.
std::vector<Table> SummaryTables(const std::vector<ReportTable>& tables, const ReportOptions& o);

}  // namespace regbench
