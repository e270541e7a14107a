#pragma once
// How reports read the typed result row (runners/result_row.hpp): per-pair metrics through
// their descriptors (core/metrics.hpp MetricField), so a metric is named by string once, where
// the options name it, and read through its field everywhere else.
#include <optional>
#include <string>
#include <vector>

#include "core/metrics.hpp"
#include "runners/result_row.hpp"

namespace regbench {

/// The metric called `name` (mae_r, mae_t, mse_r, mse_t, rre, rte, ccd, chamfer, overlap_rmse);
/// throws std::invalid_argument listing them.
const MetricField& FindMetric(const std::string& name);

/// The names FindMetric knows, in its order.
std::vector<std::string> MetricNames();

/// Decimals of the quantities that are no per-pair metric: fractions of pairs (recall,
/// success) and seconds per call.
constexpr int kFractionDecimals = 3;
constexpr int kSecondsDecimals = 5;

/// Identity of the pair file a row was measured on: its content hash when the row records one
/// (`data.content_hash`, written by `run` and `score`), else "file:<name>".
std::string RowPairFileId(const ResultRow& row);

/// The pair's measured overlap, min(source ratio, target ratio); nullopt for rows written
/// before rows recorded the ratios.
std::optional<double> MeasuredOverlap(const ResultRow& row);

/// Methods in first-seen order.
std::vector<std::string> MethodOrder(const std::vector<ResultRow>& rows);

/// The rows of `method`, in their order.
std::vector<const ResultRow*> RowsOf(const std::vector<ResultRow>& rows, const std::string& method);

}  // namespace regbench
