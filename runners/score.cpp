#include "runners/score.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/atomic_file.hpp"
#include "core/coordinate_limit.hpp"
#include "core/file_lock.hpp"
#include "core/input_file.hpp"
#include "core/json_limits.hpp"
#include "core/parse_number.hpp"
#include "protocols/pair_file.hpp"
#include "runners/result_row.hpp"
#include "runners/runner.hpp"

namespace regbench {
namespace {

bool EndsWith(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() &&
           s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// Empty when T is rigid within tol (a similarity s R with `allow_scale`, s returned in
/// *scale); otherwise what is wrong with it.
std::string RigidProblem(const Transform& T, double tol, bool allow_scale, double* scale) {
    if (!T.allFinite()) return "has non-finite entries";
    if (T.topRightCorner<3, 1>().cwiseAbs().maxCoeff() > kMaxTranslation) {
        return "translates beyond the coordinate limit (|t| <= 2e15)";
    }
    Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    char buf[200];
    *scale = 1.0;
    if (allow_scale) {
        const double det = R.determinant();
        if (!(det > 0.0)) {
            std::snprintf(buf, sizeof(buf), "has det %.6g <= 0 (not a scaled rotation)", det);
            return buf;
        }
        *scale = std::cbrt(det);
        R /= *scale;
    }
    const double ortho = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    const double det = R.determinant();
    const double bottom = (T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff();
    if (ortho > tol) {
        std::snprintf(buf, sizeof(buf), "is not a rotation%s: max |R^T R - I| = %.3g > %.3g",
                      allow_scale ? " times a scale" : "", ortho, tol);
        return buf;
    }
    if (std::abs(det - 1.0) > tol) {
        std::snprintf(buf, sizeof(buf), "is not a proper rotation: det R = %.6g", det);
        return buf;
    }
    if (bottom > tol) return "has a bottom row other than (0, 0, 0, 1)";
    return "";
}

/// A pair index from JSON or CSV text: a non-negative integer below num_pairs.
std::size_t CheckedPair(double value, std::size_t num_pairs, const std::string& where) {
    if (!(value >= 0) || std::floor(value) != value) {
        throw std::runtime_error(where + ": pair index is not a non-negative integer");
    }
    if (value >= static_cast<double>(num_pairs)) {
        // %.17g reports the index as written (1e300 was cast to -9223372036854775808).
        char text[64];
        std::snprintf(text, sizeof(text), "%.17g", value);
        throw std::runtime_error(where + ": pair " + text + " is out of range (the pair file has " +
                                 std::to_string(num_pairs) + " pairs, 0.." +
                                 std::to_string(num_pairs - 1) + ")");
    }
    return static_cast<std::size_t>(value);
}

/// Parses one JSONL line; false when it belongs to another method (rescoring a results file),
/// whose name goes into `other_methods`.
bool ParseJsonLine(const std::string& line, const std::string& where, std::size_t num_pairs,
                   const std::string& method, ExternalTransform* out,
                   std::set<std::string>* other_methods) {
    nlohmann::json j;
    try {
        j = ParseJsonBounded(line, where);
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(where + ": not JSON: " + e.what());
    }
    if (!j.is_object()) throw std::runtime_error(where + ": not a JSON object");
    if (j.contains("method") && j["method"].is_string() && j["method"] != method) {
        other_methods->insert(j["method"].get<std::string>());
        return false;
    }
    if (!j.contains("pair") || !j["pair"].is_number()) {
        throw std::runtime_error(where + ": no numeric \"pair\"");
    }
    if (!j.contains("transform")) throw std::runtime_error(where + ": no \"transform\"");
    out->pair = CheckedPair(j["pair"].get<double>(), num_pairs, where);
    try {
        out->T = TransformFromJson(j["transform"]);
    } catch (const std::exception& e) {
        throw std::runtime_error(where + ": " + e.what());
    }
    if (j.contains("content_hash") && j["content_hash"].is_string()) {
        out->content_hash = j["content_hash"].get<std::string>();
    } else if (j.contains("data") && j["data"].is_object() && j["data"].contains("content_hash") &&
               j["data"]["content_hash"].is_string()) {
        out->content_hash = j["data"]["content_hash"].get<std::string>();  // a result row
    }
    if (j.contains("seconds") && !j["seconds"].is_null()) {
        if (!j["seconds"].is_number()) throw std::runtime_error(where + ": seconds not a number");
        out->seconds = j["seconds"].get<double>();
    }
    return true;
}

/// Parses one CSV line: pair, the 12 entries of the top 3 rows or the 16 of all four rows
/// (row-major), optional seconds.
void ParseCsvLine(const std::string& line, const std::string& where, std::size_t num_pairs,
                  ExternalTransform* out) {
    std::vector<double> v;
    std::stringstream ss(line);
    std::string field;
    while (std::getline(ss, field, ',')) {
        field.erase(0, field.find_first_not_of(" \t\r"));
        field.erase(field.find_last_not_of(" \t\r") + 1);
        const std::optional<double> x = ParseNumber<double>(field);
        if (!x) {
            throw std::runtime_error(where + ": field " + std::to_string(v.size() + 1) + " ('" +
                                     field + "') is not a number");
        }
        v.push_back(*x);
    }
    const int rows = v.size() == 13 || v.size() == 14 ? 3 : v.size() == 17 || v.size() == 18 ? 4 : 0;
    if (rows == 0) {
        throw std::runtime_error(where +
                                 ": expected 13 or 14 fields (pair,t00,...,t23[,seconds]) or 17 or "
                                 "18 (pair,t00,...,t33[,seconds]), got " +
                                 std::to_string(v.size()));
    }
    out->pair = CheckedPair(v[0], num_pairs, where);
    out->T = Transform::Identity();
    for (int r = 0; r < rows; ++r) {
        for (int c = 0; c < 4; ++c) out->T(r, c) = v[static_cast<std::size_t>(1 + 4 * r + c)];
    }
    const std::size_t seconds_at = static_cast<std::size_t>(1 + 4 * rows);
    out->seconds = v.size() > seconds_at ? v[seconds_at] : 0.0;
}

/// The whitespace-separated numbers of one line of a 3DMatch .log; throws naming a non-number.
std::vector<double> LogNumbers(const std::string& line, const std::string& where) {
    std::vector<double> v;
    std::istringstream ss(line);
    std::string field;
    while (ss >> field) {
        const std::optional<double> x = ParseNumber<double>(field);
        if (!x) {
            throw std::runtime_error(where + ": field " + std::to_string(v.size() + 1) + " ('" +
                                     field + "') is not a number");
        }
        v.push_back(*x);
    }
    return v;
}

/// A 3DMatch .log record being read: its header line "i j n", then four rows of the 4x4.
struct LogRecord {
    std::string header_at;  ///< file:line of "i j n"; empty between records
    int rows = 0;           ///< matrix rows read so far
    Transform T = Transform::Identity();
};

/// Feeds one non-comment line of a .log; true when it completed a record (then *out is set,
/// its pair the record's index `records`).
bool ParseLogLine(const std::string& line, const std::string& where, std::size_t records,
                  std::size_t num_pairs, LogRecord* record, ExternalTransform* out) {
    const std::vector<double> v = LogNumbers(line, where);
    if (record->header_at.empty()) {
        if (v.size() != 3 || std::any_of(v.begin(), v.end(), [](double x) {
                return !(x >= 0) || std::floor(x) != x;
            })) {
            throw std::runtime_error(where +
                                     ": expected a record header 'i j n' (three non-negative "
                                     "integers: the fragments and their count), got " +
                                     std::to_string(v.size()) + " fields '" + line + "'");
        }
        if (records >= num_pairs) {
            throw std::runtime_error(where + ": record " + std::to_string(records + 1) +
                                     " but the pair file has " + std::to_string(num_pairs) +
                                     " pairs (a .log gives pair k as its k-th record: one "
                                     "record per pair, in pair-file order)");
        }
        record->header_at = where;
        record->rows = 0;
        return false;
    }
    if (v.size() != 4) {
        throw std::runtime_error(where + ": expected row " + std::to_string(record->rows + 1) +
                                 " of the 4x4 of the record at " + record->header_at +
                                 " (4 numbers), got " + std::to_string(v.size()) + " fields");
    }
    for (int c = 0; c < 4; ++c) record->T(record->rows, c) = v[static_cast<std::size_t>(c)];
    if (++record->rows < 4) return false;
    out->pair = records;
    out->T = record->T;
    out->origin = record->header_at;
    record->header_at.clear();
    return true;
}

std::uint64_t LittleEndian(const unsigned char* b, int bytes) {
    std::uint64_t x = 0;
    for (int i = bytes - 1; i >= 0; --i) x = (x << 8) | b[i];
    return x;
}

/// The value of `key` in a .npy header dict ("{'descr': '<f8', 'fortran_order': False,
/// 'shape': (3, 4, 4), }"): the text after "'key':" up to the next top-level ',' or '}'.
std::string NpyHeaderValue(const std::string& header, const std::string& key,
                           const std::string& path) {
    const auto at = header.find("'" + key + "'");
    if (at == std::string::npos) {
        throw std::runtime_error(path + ": not a .npy file this reader takes: its header has no '" +
                                 key + "' (header: " + header + ")");
    }
    auto i = header.find(':', at);
    if (i == std::string::npos) throw std::runtime_error(path + ": malformed .npy header");
    ++i;
    int depth = 0;
    std::string value;
    for (; i < header.size(); ++i) {
        const char c = header[i];
        if (c == '(') ++depth;
        if (c == ')') --depth;
        if (depth == 0 && (c == ',' || c == '}')) break;
        value += c;
    }
    value.erase(0, value.find_first_not_of(" "));
    value.erase(value.find_last_not_of(" ") + 1);
    return value;
}

/// Reads a NumPy .npy of shape (P, 4, 4), P = num_pairs, little-endian float64 or float32 in
/// C order (format versions 1.0, 2.0, 3.0: numpy.lib.format): element k is pair k.
std::vector<ExternalTransform> ReadNpy(const std::string& path, std::size_t num_pairs) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error(path + ": cannot open transforms file");
    in.seekg(0, std::ios::end);
    const auto file_size = static_cast<std::uint64_t>(in.tellg());
    in.seekg(0);
    unsigned char magic[12] = {};
    in.read(reinterpret_cast<char*>(magic), 10);
    static const unsigned char kMagic[6] = {0x93, 'N', 'U', 'M', 'P', 'Y'};
    if (in.gcount() != 10 || !std::equal(kMagic, kMagic + 6, magic)) {
        throw std::runtime_error(path + ": not a NumPy .npy file (no \x93NUMPY magic)");
    }
    const int major = magic[6];
    if (major < 1 || major > 3) {
        throw std::runtime_error(path + ": .npy format version " + std::to_string(major) +
                                 " is not one of 1, 2, 3");
    }
    std::uint64_t header_len = LittleEndian(magic + 8, 2);
    std::uint64_t data_at = 10;
    if (major >= 2) {  // a 4-byte header length
        in.read(reinterpret_cast<char*>(magic + 10), 2);
        header_len = LittleEndian(magic + 8, 4);
        data_at = 12;
    }
    if (!in || header_len > 65536 || data_at + header_len > file_size) {
        throw std::runtime_error(path + ": truncated or malformed .npy header");
    }
    std::string header(static_cast<std::size_t>(header_len), '\0');
    in.read(header.data(), static_cast<std::streamsize>(header_len));
    data_at += header_len;
    header.erase(header.find_last_not_of(" \n") + 1);
    if (header.empty() || header.front() != '{' || header.back() != '}') {
        throw std::runtime_error(path + ": malformed .npy header (not a dict): " + header);
    }
    const std::string descr = NpyHeaderValue(header, "descr", path);
    int bytes = 0;
    if (descr == "'<f8'") bytes = 8;
    if (descr == "'<f4'") bytes = 4;
    if (bytes == 0) {
        throw std::runtime_error(path + ": dtype " + descr +
                                 " is not little-endian float64 ('<f8') or float32 ('<f4'); "
                                 "save with a.astype('<f8')");
    }
    if (NpyHeaderValue(header, "fortran_order", path) != "False") {
        throw std::runtime_error(path +
                                 ": array is in Fortran order; save np.ascontiguousarray(a)");
    }
    const std::string shape_text = NpyHeaderValue(header, "shape", path);
    std::vector<std::uint64_t> shape;
    {
        std::string inner = shape_text;
        if (inner.size() < 2 || inner.front() != '(' || inner.back() != ')') {
            throw std::runtime_error(path + ": malformed .npy shape " + shape_text);
        }
        std::stringstream ss(inner.substr(1, inner.size() - 2));
        std::string field;
        while (std::getline(ss, field, ',')) {
            field.erase(0, field.find_first_not_of(" "));
            field.erase(field.find_last_not_of(" ") + 1);
            if (field.empty()) continue;  // the trailing comma of "(3,)"
            const auto n = ParseNumber<std::uint64_t>(field);
            if (!n) throw std::runtime_error(path + ": malformed .npy shape " + shape_text);
            shape.push_back(*n);
        }
    }
    if (shape.size() != 3 || shape[1] != 4 || shape[2] != 4) {
        throw std::runtime_error(path + ": array has shape " + shape_text +
                                 "; expected (P, 4, 4), one 4x4 transform per pair");
    }
    if (shape[0] != num_pairs) {
        throw std::runtime_error(path + ": holds " + std::to_string(shape[0]) +
                                 " transforms but the pair file has " +
                                 std::to_string(num_pairs) +
                                 " pairs (a .npy gives pair k as its k-th 4x4: one per pair, in "
                                 "pair-file order)");
    }
    const std::uint64_t data_bytes = shape[0] * 16 * static_cast<std::uint64_t>(bytes);
    if (file_size - data_at != data_bytes) {
        throw std::runtime_error(path + ": holds " + std::to_string(file_size - data_at) +
                                 " data bytes; shape " + shape_text + " of " + descr + " needs " +
                                 std::to_string(data_bytes) + " (truncated or padded file)");
    }
    std::vector<unsigned char> data(static_cast<std::size_t>(data_bytes));
    in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(data_bytes));
    if (!in) throw std::runtime_error(path + ": cannot read the .npy data");
    std::vector<ExternalTransform> out(num_pairs);
    for (std::size_t k = 0; k < num_pairs; ++k) {
        out[k].pair = k;
        out[k].origin = path + "[" + std::to_string(k) + "]";
        for (int e = 0; e < 16; ++e) {
            const unsigned char* b = data.data() + (k * 16 + static_cast<std::size_t>(e)) *
                                                       static_cast<std::size_t>(bytes);
            const std::uint64_t raw = LittleEndian(b, bytes);
            double x = 0.0;
            if (bytes == 8) {
                std::memcpy(&x, &raw, 8);
            } else {
                const auto raw32 = static_cast<std::uint32_t>(raw);
                float f = 0.0f;
                std::memcpy(&f, &raw32, 4);
                x = f;
            }
            out[k].T(e / 4, e % 4) = x;
        }
    }
    return out;
}

/// Checks one transform read from any format (seconds, rigidity, a pair given once) and keeps it.
void Accept(ExternalTransform t, double rigid_tolerance, bool allow_scale,
            std::map<std::size_t, std::string>* seen, std::vector<ExternalTransform>* out) {
    const std::string& where = t.origin;
    if (!std::isfinite(t.seconds) || t.seconds < 0) {
        throw std::runtime_error(where + ": seconds must be a finite number >= 0");
    }
    const std::string problem = RigidProblem(t.T, rigid_tolerance, allow_scale, &t.scale);
    if (!problem.empty()) {
        throw std::runtime_error(
            where + ": transform of pair " + std::to_string(t.pair) + " " + problem +
            (allow_scale ? "" : " (scoring needs a rigid transform; --allow-scale accepts s R)"));
    }
    const auto [it, fresh] = seen->emplace(t.pair, where);
    if (!fresh) {
        throw std::runtime_error(where + ": pair " + std::to_string(t.pair) +
                                 " given twice (first at " + it->second + ")");
    }
    out->push_back(t);
}

}  // namespace

TransformsFormat TransformsFormatOf(const std::string& path) {
    if (EndsWith(path, ".jsonl") || EndsWith(path, ".json")) return TransformsFormat::kJsonl;
    if (EndsWith(path, ".csv")) return TransformsFormat::kCsv;
    if (EndsWith(path, ".log")) return TransformsFormat::kLog;
    if (EndsWith(path, ".npy")) return TransformsFormat::kNpy;
    return TransformsFormat::kUnknown;
}

std::vector<ExternalTransform> ReadTransforms(const std::string& path, std::size_t num_pairs,
                                              const std::string& method, double rigid_tolerance,
                                              bool allow_scale) {
    const TransformsFormat format = TransformsFormatOf(path);
    if (format == TransformsFormat::kUnknown) {
        throw std::runtime_error(path + ": " + kTransformsExtensions);
    }
    RequireRegularFile(path);
    std::map<std::size_t, std::string> seen;  // pair -> file:line
    std::vector<ExternalTransform> out;
    if (format == TransformsFormat::kNpy) {
        for (auto& t : ReadNpy(path, num_pairs)) {
            Accept(std::move(t), rigid_tolerance, allow_scale, &seen, &out);
        }
        return out;
    }
    const bool csv = format == TransformsFormat::kCsv;
    const bool log = format == TransformsFormat::kLog;
    LogRecord record;  // .log: the record being read
    std::ifstream in(path);
    if (!in) throw std::runtime_error(path + ": cannot open transforms file");
    std::string line;
    std::size_t lineno = 0;
    std::string file_hash;                // from a "# content_hash: H" comment
    std::set<std::string> other_methods;  // "method" names of the JSONL rows skipped
    while (std::getline(in, line)) {
        ++lineno;
        const auto first = line.find_first_not_of(" \t\r");
        if (first == std::string::npos) continue;
        if (line[first] == '#') {
            static const std::string kKey = "content_hash:";
            const auto key = line.find(kKey, first);
            if (key != std::string::npos) {
                file_hash = line.substr(key + kKey.size());
                file_hash.erase(0, file_hash.find_first_not_of(" \t"));
                file_hash.erase(file_hash.find_last_not_of(" \t\r") + 1);
            }
            continue;
        }
        const std::string where = path + ":" + std::to_string(lineno);
        ExternalTransform t;
        t.origin = where;
        if (csv) {
            if (line.compare(first, 4, "pair") == 0) continue;  // header
            ParseCsvLine(line, where, num_pairs, &t);
        } else if (log) {
            if (!ParseLogLine(line, where, out.size(), num_pairs, &record, &t)) continue;
        } else if (!ParseJsonLine(line, where, num_pairs, method, &t, &other_methods)) {
            continue;
        }
        if (t.content_hash.empty()) t.content_hash = file_hash;
        Accept(std::move(t), rigid_tolerance, allow_scale, &seen, &out);
    }
    if (log && !record.header_at.empty()) {
        throw std::runtime_error(record.header_at + ": the record ends after " +
                                 std::to_string(record.rows) +
                                 " of the 4 rows of its 4x4 (truncated file)");
    }
    if (log && out.size() != num_pairs) {
        throw std::runtime_error(path + ": holds " + std::to_string(out.size()) +
                                 " records but the pair file has " + std::to_string(num_pairs) +
                                 " pairs (a .log gives pair k as its k-th record: one record per "
                                 "pair, in pair-file order)");
    }
    // Rows of other methods only: --method is most likely a typo or the wrong file, and scoring
    // would turn every pair into a `missing` row scored as the identity.
    if (out.empty() && !other_methods.empty()) {
        std::string names;
        for (const auto& m : other_methods) names += (names.empty() ? "'" : ", '") + m + "'";
        throw std::runtime_error(path + ": no rows of method '" + method + "'; it holds rows of " +
                                 names + " (pick one with --method)");
    }
    return out;
}

ScoreSummary ScoreTransforms(const ScoreOptions& o) {
    if (o.method.empty()) throw std::invalid_argument("score: --method is required");
    if (o.out_path.empty()) throw std::invalid_argument("score: --out is required");
    if (!o.params.is_object()) throw std::invalid_argument("score: --params must be a JSON object");
    CheckMetricOptions(o.metric_options);
    // Refused before any work: a directory, a device or one of the inputs as --out.
    CheckOutputPath(o.out_path, {o.pairs_path, o.transforms_path});
    // One writer per output for the whole scoring, as `run` (a second `score` or a `run` on
    // the same --out is refused naming this pid).
    const OutputLock lock(o.out_path);
    const PairSet set = ReadPairFile(o.pairs_path);  // throws naming the file
    const std::vector<ExternalTransform> given = ReadTransforms(
        o.transforms_path, set.pairs.size(), o.method, o.rigid_tolerance, o.allow_scale);
    std::vector<const ExternalTransform*> by_pair(set.pairs.size(), nullptr);
    for (const auto& t : given) by_pair[t.pair] = &t;

    RowContext context;
    context.threads = o.threads;
    context.euler = o.euler;
    context.metric_options =
        PairMetricOptions(o.pairs_path, set, o.metric_options, o.ccd_clip_given);
    context.data = DataTagOf(o.pairs_path, set);
    // Transforms computed on other pairs would be scored against the wrong ground truth.
    for (const auto& t : given) {
        if (!t.content_hash.empty() && t.content_hash != context.data.content_hash) {
            throw std::runtime_error(t.origin +
                                     ": the transform was computed on the pair file "
                                     "with content hash " +
                                     t.content_hash + ", not on " + o.pairs_path + " (" +
                                     context.data.content_hash +
                                     "); score it against the pair file it was computed on");
        }
        if (t.content_hash.empty() && !o.allow_unhashed) {
            throw std::runtime_error(
                t.origin +
                ": the transform records no content hash of the pair file it was computed "
                "on, so nothing shows it belongs to " +
                o.pairs_path + "; add a \"content_hash\" key (JSONL) or a '# content_hash: " +
                context.data.content_hash +
                "' line (CSV, .log; the scored file's hash), or pass --allow-unhashed to score it "
                "anyway (a .npy cannot record one)");
        }
    }
    const std::string scale = PairScaleWarning(set, context.metric_options);
    if (!scale.empty()) std::fprintf(stderr, "[score] warning: %s\n", scale.c_str());
    const MethodSpec spec{o.method, o.params};
    ScoreSummary summary;
    std::vector<ResultRow> rows;
    for (std::size_t k = 0; k < set.pairs.size(); ++k) {
        AlignResult result;
        if (by_pair[k]) {
            result.T_target_source = by_pair[k]->T;
            result.seconds = by_pair[k]->seconds;
            result.scale = by_pair[k]->scale;
            context.status = Status::kOk;
        } else {
            // Scored as the identity, like a failed run row, and counted as failed by reports.
            result.status = AlignStatus::kFailed;
            result.message = "no transform for this pair in " + o.transforms_path;
            result.stop_reason = ToString(Status::kMissing);
            context.status = Status::kMissing;
            ++summary.missing;
        }
        rows.push_back(MakeResultRow(k, set.pairs[k], spec, result, context));
    }
    WriteResultRows(o.out_path, rows, {o.pairs_path, o.transforms_path});
    summary.rows = rows.size();
    return summary;
}

}  // namespace regbench
