#pragma once
// Read-only accessors for JSONL result rows as `regbench run` writes them. The reports go
// through these so a change of row schema is handled in one place.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/metrics.hpp"

namespace regbench {

/// A per-pair metric as reports read it: its name (the JSONL `metrics` key, the CLI's), its
/// field of the typed row, and the one number format tables print it with.
struct MetricField {
    const char* name;
    double PairMetrics::*field;
    int decimals;
};

/// The metric called `name` (mae_r, mae_t, mse_r, mse_t, rre, rte, ccd, chamfer, overlap_rmse);
/// throws std::invalid_argument listing them.
const MetricField& FindMetric(const std::string& name);

/// The names FindMetric knows, in its order.
std::vector<std::string> MetricNames();

/// Decimals of the quantities that are no per-pair metric: fractions of pairs (recall,
/// success) and seconds per call.
constexpr int kFractionDecimals = 3;
constexpr int kSecondsDecimals = 5;

/// The pair file's name as recorded in the row's `data` ("?" when absent).
std::string RowPairFileName(const nlohmann::json& row);

/// Identity of the pair file a row was measured on: its content hash when the row records one
/// (`data.content_hash`, written by `run` and `score`), else "file:<name>".
std::string RowPairFileId(const nlohmann::json& row);

/// A metric of the row (a name FindMetric knows), or nullopt when missing, null or not finite.
std::optional<double> RowMetric(const nlohmann::json& row, const std::string& key);

/// The row's status string ("failed" when absent).
std::string RowStatus(const nlohmann::json& row);

/// Measured source / target overlap ratio of the row's pair (top-level or under `data`).
std::optional<double> RowOverlap(const nlohmann::json& row, const char* which);

}  // namespace regbench
