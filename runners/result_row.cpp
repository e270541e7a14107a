#include "runners/result_row.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "core/atomic_file.hpp"
#include "core/coordinate_limit.hpp"
#include "core/enum_names.hpp"
#include "core/input_file.hpp"
#include "core/json_limits.hpp"
#include "core/transform.hpp"

namespace regbench {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

constexpr EnumName<Status> kStatusNames[] = {
    {Status::kOk, "ok"},           {Status::kFailed, "failed"},   {Status::kTimeout, "timeout"},
    {Status::kCrashed, "crashed"}, {Status::kMissing, "missing"},
};

/// NaN / Inf become null (nlohmann would write null for them anyway; this says so).
nlohmann::json FiniteOrNull(double x) { return std::isfinite(x) ? nlohmann::json(x) : nullptr; }

/// null reads back as NaN, so a row whose metric could not be computed stays readable.
double NumberOrNaN(const nlohmann::json& j, const char* key) {
    const auto it = j.find(key);
    if (it == j.end()) throw std::invalid_argument(std::string("metrics has no '") + key + "'");
    if (it->is_null()) return kNaN;
    if (!it->is_number()) {
        throw std::invalid_argument(std::string("metrics.") + key + " is not a number");
    }
    return it->get<double>();
}

/// A point count that old rows may lack: nullopt when absent; anything but a whole number
/// >= 0 throws naming the key.
std::optional<std::size_t> OptionalCount(const nlohmann::json& j, const char* key) {
    const auto it = j.find(key);
    if (it == j.end()) return std::nullopt;
    if (!it->is_number_unsigned()) {
        throw std::invalid_argument(std::string(key) + " must be a whole number >= 0, got " +
                                    it->dump());
    }
    return it->get<std::size_t>();
}

/// A number that old rows may lack: nullopt when absent; a key of another type throws.
std::optional<double> OptionalNumber(const nlohmann::json& j, const char* key) {
    const auto it = j.find(key);
    if (it == j.end()) return std::nullopt;
    if (!it->is_number()) throw std::invalid_argument(std::string(key) + " is not a number");
    return it->get<double>();
}

nlohmann::json MetricsToJson(const PairMetrics& m) {
    nlohmann::json j = {{"ccd_within_clip", m.ccd_within_clip}};
    for (const auto& f : PerPairMetrics()) j[f.name] = FiniteOrNull(m.*f.field);
    // Keys only rows measured with non-default options carry (rows at the defaults keep
    // their bytes): the CCD clip, and Open3D's fitness / inlier RMSE at their threshold.
    if (m.ccd_clip != kCcdClip) j["ccd_clip"] = m.ccd_clip;
    if (m.inlier_threshold > 0.0) {
        j["inlier_threshold"] = m.inlier_threshold;
        j["fitness"] = FiniteOrNull(m.fitness);
        j["inlier_rmse"] = FiniteOrNull(m.inlier_rmse);
    }
    return j;
}

PairMetrics MetricsFromJson(const nlohmann::json& j, EulerConvention euler) {
    if (!j.is_object()) throw std::invalid_argument("metrics is not an object");
    PairMetrics m;
    m.euler = euler;
    for (const auto& f : PerPairMetrics()) {
        // overlap_rmse came later than the others: older rows have none (NaN, so 3DMatch
        // recall refuses them).
        const bool old_row = f.field == &PairMetrics::overlap_rmse && !j.contains(f.name);
        m.*f.field = old_row ? kNaN : NumberOrNaN(j, f.name);
    }
    m.ccd_within_clip = j.value("ccd_within_clip", true);
    m.ccd_clip = OptionalNumber(j, "ccd_clip").value_or(kCcdClip);
    m.inlier_threshold = OptionalNumber(j, "inlier_threshold").value_or(0.0);
    if (m.inlier_threshold > 0.0) {
        m.fitness = NumberOrNaN(j, "fitness");
        m.inlier_rmse = NumberOrNaN(j, "inlier_rmse");
    }
    return m;
}

/// Keys ResultRow reads itself; everything else goes to `other`.
const char* const kKnownKeys[] = {"pair",
                                  "method",
                                  "params",
                                  "transform",
                                  "seconds",
                                  "cpu_seconds",
                                  "cpu_scope",
                                  "machine",
                                  "iterations",
                                  "status",
                                  "message",
                                  "stop_reason",
                                  "scale",
                                  "extra",
                                  "threads",
                                  "shape",
                                  "category",
                                  "source_overlap_ratio",
                                  "target_overlap_ratio",
                                  "source_points",
                                  "target_points",
                                  "euler",
                                  "metrics",
                                  "gt_transform",
                                  "data"};

bool IsKnownKey(const std::string& key) {
    for (const char* k : kKnownKeys) {
        if (key == k) return true;
    }
    return false;
}

/// The largest metric a writer can produce: coordinates are limited to 1e15
/// (core/coordinate_limit.hpp), so squared distances stay near 1e31; far above is damage.
constexpr double kMaxMetric = 1e35;
/// mae_r averages three Euler-angle differences of at most 360 deg each; rre is an angle in
/// [0, 180]; mse_r squares the former (a hair of slack for round-off).
constexpr double kAngleSlack = 1e-6;

void CheckMetricBounds(const nlohmann::json& metrics) {
    for (const auto& f : PerPairMetrics()) {
        const auto it = metrics.find(f.name);
        if (it == metrics.end() || it->is_null()) {
            // overlap_rmse alone may be absent or null (rows from before it existed); every
            // other metric is computed from a finite transform and written as a number.
            if (std::string(f.name) == "overlap_rmse") continue;
            throw std::invalid_argument(std::string("metrics.") + f.name +
                                        " is missing or null (a writer always gives a number)");
        }
        const double v = it->get<double>();
        double most = kMaxMetric;
        if (std::string(f.name) == "mae_r") most = 360.0 + kAngleSlack;
        if (std::string(f.name) == "mse_r") most = 360.0 * 360.0 + kAngleSlack;
        if (std::string(f.name) == "rre") most = 180.0 + kAngleSlack;
        if (!(v >= 0.0 && v <= most)) {
            throw std::invalid_argument(std::string("metrics.") + f.name + " = " +
                                        nlohmann::json(v).dump() + " is outside [0, " +
                                        nlohmann::json(most).dump() + "]");
        }
    }
}

void CheckMatrix(const Transform& T, const char* name, bool rigid) {
    if (!T.allFinite()) throw std::invalid_argument(std::string(name) + " is not finite");
    if (T.topRightCorner<3, 1>().cwiseAbs().maxCoeff() > kMaxTranslation) {
        throw std::invalid_argument(std::string(name) +
                                    " translates beyond the coordinate limit (2e15)");
    }
    const bool last_row = T(3, 0) == 0.0 && T(3, 1) == 0.0 && T(3, 2) == 0.0 && T(3, 3) == 1.0;
    if (rigid && (!last_row || !IsRotation(T.topLeftCorner<3, 3>(), 1e-6))) {
        throw std::invalid_argument(std::string(name) + " is not a rigid transform");
    }
}

}  // namespace

void CheckRowAsWritten(const nlohmann::json& j, const ResultRow& row) {
    const auto pair = j.find("pair");
    if (pair == j.end() || !pair->is_number_unsigned() || row.pair > kMaxPairIndex) {
        throw std::invalid_argument("pair must be a whole number in [0, " +
                                    std::to_string(kMaxPairIndex) + "], got " +
                                    (pair == j.end() ? std::string("none") : pair->dump()));
    }
    if (row.method.empty()) throw std::invalid_argument("method is empty");
    CheckMetricBounds(j.at("metrics"));
    CheckMatrix(row.result.T_target_source, "transform", false);
    if (row.gt_transform) CheckMatrix(*row.gt_transform, "gt_transform", true);
    if (!std::isfinite(row.result.seconds)) throw std::invalid_argument("seconds is not finite");
}

const char* ToString(Status status) { return EnumToString(kStatusNames, status); }

Status ParseStatus(const std::string& name) {
    if (const auto status = FindEnum(kStatusNames, name)) return *status;
    throw std::invalid_argument("unknown status '" + name + "' (expected " +
                                EnumNameList(kStatusNames, ", ", " or ") + ")");
}

void to_json(nlohmann::json& j, Status status) { j = ToString(status); }
void from_json(const nlohmann::json& j, Status& status) {
    status = ParseStatus(j.get<std::string>());
}

void to_json(nlohmann::json& j, const DataTag& d) {
    j = {{"pairs_file", d.pairs_file},
         {"dataset", d.dataset},
         {"protocol", d.protocol},
         {"pairing", d.pairing},
         {"seed", d.seed}};
    if (!d.content_hash.empty()) j["content_hash"] = d.content_hash;
    if (!d.dataset_sha256.empty()) j["dataset_sha256"] = d.dataset_sha256;
    if (d.scale != 1.0) j["scale"] = d.scale;  // unit-sphere rows stay as they were
}

void from_json(const nlohmann::json& j, DataTag& d) {
    d.pairs_file = j.value("pairs_file", "unknown");
    d.dataset = j.value("dataset", "unknown");
    d.protocol = j.value("protocol", "unknown");
    d.pairing = j.value("pairing", "unknown");
    d.seed = j.value("seed", nlohmann::json());
    d.content_hash = j.value("content_hash", "");
    d.dataset_sha256 = j.value("dataset_sha256", "");
    d.scale = j.value("scale", 1.0);
    if (!std::isfinite(d.scale) || d.scale <= 0.0) {
        throw std::invalid_argument("data.scale must be a finite number > 0, got " +
                                    j.at("scale").dump());
    }
}

nlohmann::json TransformToJson(const Transform& T) {
    nlohmann::json rows = nlohmann::json::array();
    for (int r = 0; r < 4; ++r) rows.push_back({T(r, 0), T(r, 1), T(r, 2), T(r, 3)});
    return rows;
}

Transform TransformFromJson(const nlohmann::json& j) {
    if (!j.is_array() || j.size() != 4) throw std::invalid_argument("transform is not 4x4");
    Transform T;
    for (int r = 0; r < 4; ++r) {
        const auto& row = j[static_cast<std::size_t>(r)];
        if (!row.is_array() || row.size() != 4) {
            throw std::invalid_argument("transform row " + std::to_string(r) +
                                        " does not hold 4 numbers");
        }
        for (int c = 0; c < 4; ++c) {
            const auto& v = row[static_cast<std::size_t>(c)];
            if (!v.is_number()) {
                throw std::invalid_argument("transform entry (" + std::to_string(r) + ", " +
                                            std::to_string(c) + ") is not a number");
            }
            T(r, c) = v.get<double>();
        }
    }
    return T;
}

void to_json(nlohmann::json& j, const AlignResult& r) {
    j = {{"transform", TransformToJson(r.T_target_source)},
         {"iterations", r.iterations},
         {"stop_reason", r.stop_reason},
         {"seconds", r.seconds},
         {"cpu_seconds", r.cpu_seconds},
         {"cpu_scope", r.cpu_scope},
         {"status", ToString(r.status)},
         {"message", r.message},
         {"scale", r.scale},
         {"extra", r.extra}};
}

void from_json(const nlohmann::json& j, AlignResult& r) {
    r.T_target_source =
        j.contains("transform") ? TransformFromJson(j.at("transform")) : Transform::Identity();
    r.iterations = j.value("iterations", 0);
    r.stop_reason = j.value("stop_reason", "");
    r.seconds = j.value("seconds", 0.0);
    // Rows from before CPU timing existed read as 0 s of the calling thread.
    r.cpu_seconds = j.value("cpu_seconds", 0.0);
    r.cpu_scope = j.value("cpu_scope", "thread");
    r.status = j.value("status", "ok") == "ok" ? AlignStatus::kOk : AlignStatus::kFailed;
    r.message = j.value("message", "");
    r.scale = j.value("scale", 1.0);
    r.extra = j.value("extra", nlohmann::json::object());
}

void to_json(nlohmann::json& j, const ResultRow& row) {
    j = row.other.is_object() ? row.other : nlohmann::json::object();
    j.update(nlohmann::json(row.result));
    j["pair"] = row.pair;
    j["method"] = row.method;
    j["params"] = row.params;
    j["status"] = row.status;
    j["threads"] = row.threads;
    j["shape"] = row.shape;
    j["category"] = row.category;
    if (row.source_overlap_ratio) j["source_overlap_ratio"] = *row.source_overlap_ratio;
    if (row.target_overlap_ratio) j["target_overlap_ratio"] = *row.target_overlap_ratio;
    if (row.source_points) j["source_points"] = *row.source_points;
    if (row.target_points) j["target_points"] = *row.target_points;
    j["euler"] = ToString(row.euler);
    j["metrics"] = MetricsToJson(row.metrics);
    if (row.gt_transform) j["gt_transform"] = TransformToJson(*row.gt_transform);
    j["data"] = row.data;
    if (!row.machine.empty()) j["machine"] = row.machine;
}

void from_json(const nlohmann::json& j, ResultRow& row) {
    if (!j.is_object()) throw std::invalid_argument("row is not a JSON object");
    for (const char* key : {"pair", "method", "metrics"}) {
        if (!j.contains(key)) throw std::invalid_argument(std::string("row has no '") + key + "'");
    }
    // A float (1e20) or negative pair would be cast out of range by get<size_t>.
    if (!j.at("pair").is_number_unsigned()) {
        throw std::invalid_argument("pair must be a whole number >= 0, got " + j.at("pair").dump());
    }
    row.pair = j.at("pair").get<std::size_t>();
    row.method = j.at("method").get<std::string>();
    row.params = j.value("params", nlohmann::json::object());
    row.status = j.contains("status") ? j.at("status").get<Status>() : Status::kOk;
    row.result = j.get<AlignResult>();
    row.threads = j.value("threads", 1);
    row.shape = j.value("shape", "");
    row.category = j.value("category", "");
    row.source_overlap_ratio = OptionalNumber(j, "source_overlap_ratio");
    row.target_overlap_ratio = OptionalNumber(j, "target_overlap_ratio");
    row.source_points = OptionalCount(j, "source_points");
    row.target_points = OptionalCount(j, "target_points");
    // Rows from before the key existed were scored with the xyz decomposition.
    row.euler = j.contains("euler") ? ParseEulerConvention(j.at("euler").get<std::string>())
                                    : EulerConvention::kXyz;
    row.metrics = MetricsFromJson(j.at("metrics"), row.euler);
    row.gt_transform.reset();
    if (j.contains("gt_transform")) row.gt_transform = TransformFromJson(j.at("gt_transform"));
    row.data = j.contains("data") ? j.at("data").get<DataTag>() : DataTag{};
    row.machine = j.value("machine", nlohmann::json::object());
    row.other = nlohmann::json::object();
    for (const auto& item : j.items()) {
        if (!IsKnownKey(item.key())) row.other[item.key()] = item.value();
    }
}

std::string ToJsonLine(const ResultRow& row) {
    // A method's message may carry a library's non-UTF-8 bytes (a path, a file's content):
    // written with U+FFFD for them instead of throwing a bare type_error.316 mid-run.
    return nlohmann::json(row).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

void ForEachJsonlLine(
    const std::string& path, TornLastLine torn,
    const std::function<void(const std::string& where, const nlohmann::json& value)>& visit) {
    RequireRegularFile(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error(path + ": cannot open results file");
    // A pair file given where result rows belong (`report pairs.h5`) is named as one, with the
    // commands that read it, instead of "line 1: not JSON".
    static constexpr char kHdf5Signature[] = "\x89HDF\r\n\x1a\n";
    char head[8] = {};
    in.read(head, sizeof head);
    if (in.gcount() == 8 && std::equal(head, head + 8, kHdf5Signature)) {
        throw std::runtime_error(path +
                                 ": a pair file (HDF5), not JSONL result rows: `regbench inspect " +
                                 path + "` describes it; `regbench run --pairs " + path +
                                 " --methods ...` writes result rows from it");
    }
    in.clear();
    in.seekg(0);
    std::string line;
    std::size_t lineno = 0;
    while (std::getline(in, line)) {
        ++lineno;
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
        const std::string where = path + ":" + std::to_string(lineno);
        // nlohmann skips a byte-order mark; no regbench writer puts one on any line.
        if (line.rfind("\xEF\xBB\xBF", 0) == 0) {
            throw std::runtime_error(where +
                                     ": starts with a byte-order mark (not a line any "
                                     "regbench writer wrote)");
        }
        nlohmann::json value;
        try {
            value = ParseJsonBounded(line, where);  // depth-limited: no stack overflow later
        } catch (const nlohmann::json::exception& e) {
            // getline sets eof only when the last line ended without a newline.
            if (torn == TornLastLine::kSkip && in.eof()) break;
            throw std::runtime_error(where + ": not JSON: " + e.what());
        }
        visit(where, value);
    }
}

std::vector<nlohmann::json> ReadJsonl(const std::string& path) {
    std::vector<nlohmann::json> rows;
    ForEachJsonlLine(path, TornLastLine::kRefuse,
                     [&](const std::string& where, const nlohmann::json& value) {
                         if (!value.is_object()) {
                             throw std::runtime_error(where + ": not a JSON object");
                         }
                         rows.push_back(value);
                     });
    return rows;
}

std::vector<ResultRow> ReadResultRows(const std::string& path) {
    std::vector<ResultRow> rows;
    ForEachJsonlLine(path, TornLastLine::kRefuse,
                     [&](const std::string& where, const nlohmann::json& value) {
                         try {
                             rows.push_back(value.get<ResultRow>());
                             CheckRowAsWritten(value, rows.back());
                         } catch (const std::exception& e) {
                             throw std::runtime_error(where + ": not a result row: " + e.what());
                         }
                         rows.back().origin = where;
                     });
    return rows;
}

void WriteResultRows(const std::string& path, const std::vector<ResultRow>& rows,
                     const std::vector<std::string>& inputs) {
    std::string text;
    for (const auto& r : rows) text += ToJsonLine(r) + "\n";
    WriteFileAtomic(path, text, inputs);
}

}  // namespace regbench
