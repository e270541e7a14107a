#pragma once
// Read-only accessors for JSONL result rows as `regbench run` writes them. The reports go
// through these so a change of row schema is handled in one place.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace regbench {

/// The pair file's name as recorded in the row's `data` ("?" when absent).
std::string RowPairFileName(const nlohmann::json& row);

/// Identity of the pair file a row was measured on: its content hash when the row records one
/// (`data.content_hash`, written by `run` and `score`), else "file:<name>".
std::string RowPairFileId(const nlohmann::json& row);

/// A metric of the row, or nullopt when missing, null or not finite.
std::optional<double> RowMetric(const nlohmann::json& row, const std::string& key);

/// The row's status string ("failed" when absent).
std::string RowStatus(const nlohmann::json& row);

/// Measured source / target overlap ratio of the row's pair (top-level or under `data`).
std::optional<double> RowOverlap(const nlohmann::json& row, const char* which);

}  // namespace regbench
