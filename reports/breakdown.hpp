#pragma once
// Beyond means: per-method distributions, failure counts, recall curves, per-category and
// per-overlap tables of one result set, as report tables (reports/table.hpp).
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "reports/statistics.hpp"
#include "reports/table.hpp"
#include "runners/result_row.hpp"

namespace regbench {

struct BreakdownOptions {
    std::vector<std::string> metrics = {"mae_r", "mae_t", "ccd", "rre", "rte"};  ///< summarised
    std::string key_metric = "mae_r";  ///< used by the category and overlap tables
    /// recall@(r, t) = fraction of pairs with mae_r < r [deg] and mae_t < t.
    std::vector<std::pair<double, double>> recall = {{1.0, 0.01}, {1.0, 0.1},  {2.0, 0.05},
                                                     {5.0, 0.1},  {10.0, 0.1}, {20.0, 0.2}};
    /// Bin edges of the pair's measured overlap, min(source ratio, target ratio).
    std::vector<double> overlap_edges = {0.0, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0001};
    /// Difficulty bins (easy / medium / hard, DifficultyTable): the ground truth's rotation
    /// angle [deg] and translation length [data units] (ascending: easy first), and the
    /// measured overlap (ascending: hard first). The last edge closes its bin.
    std::vector<double> rotation_edges = {0.0, 30.0, 60.0, 180.0};
    std::vector<double> translation_edges = {0.0, 0.3, 0.6, 1e300};
    std::vector<double> difficulty_overlap_edges = {0.0, 0.5, 0.7, 1.0};
    int bootstrap_samples = 1000;
    std::uint64_t seed = kDefaultBootstrapSeed;  ///< streams derive from method and metric
};

/// Mean ± 95% bootstrap half-width, median and std of every metric, per method.
Table DistributionTable(const std::vector<ResultRow>& rows, const BreakdownOptions& o);

/// Calls per status (ok, failed, timeout, crashed, other: `missing`) plus rows whose mae_r or
/// mae_t is not finite ("null metrics", counted as failures of the metric).
Table StatusTable(const std::vector<ResultRow>& rows);

/// recall@(r, t) for every threshold pair of the options.
Table RecallTable(const std::vector<ResultRow>& rows, const BreakdownOptions& o);

/// Mean key metric per method and shape category (columns sorted by name).
Table CategoryTable(const std::vector<ResultRow>& rows, const BreakdownOptions& o);

/// Mean key metric per method and bin of measured overlap (min of the two ratios); rows
/// without overlap ratios are left out and a note says how many.
Table OverlapTable(const std::vector<ResultRow>& rows, const BreakdownOptions& o);

/// What makes a pair hard: the size of the motion to recover or the overlap.
enum class Difficulty {
    kRotation,     ///< the rotation angle of the pair's ground truth (geodesic, degrees)
    kTranslation,  ///< the length of its translation (data units)
    kOverlap,      ///< its measured overlap, min(source ratio, target ratio)
};
/// "rotation", "translation", "overlap".
const char* ToString(Difficulty d);

/// The difficulty of one row's pair on `axis`, from the row alone (its gt_transform or overlap
/// ratios); nullopt for rows written before rows recorded them.
std::optional<double> DifficultyOf(const ResultRow& row, Difficulty axis);

/// Mean key metric per method in the easy / medium / hard bins of `axis` (BreakdownOptions'
/// edges), each cell with its pair count (n); rows without the value are left out and a note
/// says how many.
Table DifficultyTable(const std::vector<ResultRow>& rows, const BreakdownOptions& o,
                      Difficulty axis);

/// DifficultyTable of every axis.
std::vector<Table> DifficultyTables(const std::vector<ResultRow>& rows, const BreakdownOptions& o);

}  // namespace regbench
