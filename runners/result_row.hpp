#pragma once
// One typed result row: the JSONL schema that `run` and `score` write and `report` reads
// (docs/benchmark-format.md lists the keys). Everything that reads or writes rows goes through
// this file, so a key is spelt in one place.
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/metrics.hpp"
#include "core/point_cloud.hpp"
#include "core/registration.hpp"

namespace regbench {

/// Outcome of one (pair, method) call as the runner saw it.
enum class Status {
    kOk,       ///< the method returned a transform
    kFailed,   ///< the method reported a failure (its transform is the identity fallback)
    kTimeout,  ///< killed after --timeout seconds
    kCrashed,  ///< the isolated child died (signal) or returned no result
    kMissing,  ///< `score`: the transforms file has no transform for this pair
};
/// "ok", "failed", "timeout", "crashed", "missing".
const char* ToString(Status status);
/// Inverse of ToString; throws std::invalid_argument naming the value.
Status ParseStatus(const std::string& name);
void to_json(nlohmann::json& j, Status status);
void from_json(const nlohmann::json& j, Status& status);

/// Which data a row was computed on (the pair file's provenance), carried by every row.
struct DataTag {
    std::string pairs_file = "unknown";  ///< file name of the pair file (no directory)
    std::string dataset = "unknown";
    std::string protocol = "unknown";
    std::string pairing = "unknown";
    nlohmann::json seed;         ///< generation seed (null when unknown)
    std::string content_hash;    ///< hash of the pair file's arrays; empty in old rows
    std::string dataset_sha256;  ///< sha256 of the dataset file it came from (a single .h5 etc.)
    /// The pair file's `scale` (the factor `generate --scale` multiplied its lengths by; 1 for
    /// unit-sphere pairs, and in rows written before it was recorded): the default distance
    /// thresholds of `run` and `report` are their unit-sphere values times this.
    double scale = 1.0;
};
void to_json(nlohmann::json& j, const DataTag& d);
void from_json(const nlohmann::json& j, DataTag& d);

/// A call's result under the keys a row stores it by ("transform", "seconds", "cpu_seconds",
/// "cpu_scope", "iterations", "status", "message", "stop_reason", "scale", "extra"); also what
/// an isolated child sends back through its pipe. A missing key reads as AlignResult's default
/// (rows written before the key existed); any status but "ok" reads as failed.
void to_json(nlohmann::json& j, const AlignResult& r);
void from_json(const nlohmann::json& j, AlignResult& r);

/// One JSONL line. Keys are those rows have always had (so old files read) plus `euler`,
/// `source_overlap_ratio`, `target_overlap_ratio`, `source_points`, `target_points`,
/// `cpu_seconds`, `cpu_scope`, `machine`; keys this
/// struct does not know are kept in `other` and written back, so a newer writer's columns survive a
/// round trip.
struct ResultRow {
    std::size_t pair = 0;                              ///< index in the pair file
    std::string method;                                ///< registry name (or `score --method`)
    nlohmann::json params = nlohmann::json::object();  ///< the method's full parameters
    /// The call's result: transform, times, iterations, stop reason, message, scale, extras.
    /// Its ok/failed `status` follows `status` below when a row is read back.
    AlignResult result;
    Status status = Status::kOk;  ///< the runner's verdict (adds timeouts and crashes)
    int threads = 1;              ///< OpenMP threads of the call
    std::string shape;            ///< the pair's mesh / scan name
    std::string category;
    /// From the pair file (fraction labelled overlapping); absent in rows written before rows
    /// recorded them (and then not written back).
    std::optional<double> source_overlap_ratio;
    std::optional<double> target_overlap_ratio;
    /// Points of the source and target clouds the method was given (fewer than the pair's
    /// under `run --downsample`); absent in rows written before rows recorded them.
    std::optional<std::size_t> source_points;
    std::optional<std::size_t> target_points;
    /// Euler angles behind metrics.mae_r / mse_r. Rows written before this key existed were
    /// computed with today's `xyz` decomposition, so a missing key reads as kXyz.
    EulerConvention euler = EulerConvention::kZyx;
    /// Metrics against the pair's ground truth; NaN where not finite (written as JSON null).
    PairMetrics metrics;
    /// Ground truth T_gt of the pair: lets `report --euler` recompute the rotation metrics in
    /// another convention. Absent in old rows.
    std::optional<Transform> gt_transform;
    DataTag data;
    /// Machine load when the run started: {"loadavg": [1, 5, 15 min], "cores", "jobs"};
    /// empty in old rows and in `score` rows.
    nlohmann::json machine = nlohmann::json::object();
    nlohmann::json other = nlohmann::json::object();  ///< unknown keys, kept verbatim

    /// Where the row was read from ("file:line"); empty for rows made in memory. Not written.
    std::string origin;
};
void to_json(nlohmann::json& j, const ResultRow& row);
/// Throws nlohmann::json::exception / std::invalid_argument on a missing or mistyped key.
void from_json(const nlohmann::json& j, ResultRow& row);

/// Transform as 4 rows of 4 numbers.
nlohmann::json TransformToJson(const Transform& T);
/// Inverse of TransformToJson; throws std::invalid_argument unless j is 4x4 numbers.
Transform TransformFromJson(const nlohmann::json& j);

/// One compact JSON line (no newline).
std::string ToJsonLine(const ResultRow& row);

/// What a JSONL reader does with a last line that has no newline and does not parse.
enum class TornLastLine {
    kRefuse,  ///< a damaged file: throw like any other bad line
    kSkip,    ///< the write a kill cut short (a run's .part file): drop it, it is redone
};

/// The one JSONL line scanner every reader here and in merge/resume uses: calls
/// visit(where, value) for each non-blank line in order, `where` being "path:line". Throws
/// "path: cannot open results file" or "where: not JSON: ..." (see TornLastLine).
void ForEachJsonlLine(
    const std::string& path, TornLastLine torn,
    const std::function<void(const std::string& where, const nlohmann::json& value)>& visit);

/// Reads a JSONL file of objects (blank lines skipped). Throws naming file and line.
std::vector<nlohmann::json> ReadJsonl(const std::string& path);
/// The largest pair index a row may hold (no pair file holds more pairs).
inline constexpr std::size_t kMaxPairIndex = 2147483647;

/// Refuses (std::invalid_argument naming the key) a row no regbench writer would have written:
/// `pair` not a whole number in [0, kMaxPairIndex] (-1, 2.5, 1e20), an empty method, a metric
/// that is null (overlap_rmse excepted), negative or beyond what coordinates within the limit
/// give (mae_r <= 360, rre <= 180 deg, others <= 1e35), a non-finite transform or one
/// translating beyond 2e15, a non-rigid gt_transform, non-finite seconds. `j` is the
/// row's JSON, `row` what from_json made of it. Every file reader calls it (issue 44).
void CheckRowAsWritten(const nlohmann::json& j, const ResultRow& row);

/// Reads and types every row; a row that does not parse or fails CheckRowAsWritten throws
/// naming file:line and the key.
/// Each row's `origin` is set to "path:line".
std::vector<ResultRow> ReadResultRows(const std::string& path);
/// Writes rows (one per line) to path atomically and checked (core/atomic_file): readers never
/// see half a file, a write error (full disk, file-size limit) throws naming the path, and
/// `inputs` (the files the rows came from) are never replaced.
void WriteResultRows(const std::string& path, const std::vector<ResultRow>& rows,
                     const std::vector<std::string>& inputs = {});

}  // namespace regbench
