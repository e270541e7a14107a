#include "runners/score.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
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

/// Parses one CSV line: pair, the 12 entries of the top 3 rows, optional seconds.
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
    if (v.size() != 13 && v.size() != 14) {
        throw std::runtime_error(where +
                                 ": expected 13 or 14 fields (pair,t00,...,t23[,seconds]), got " +
                                 std::to_string(v.size()));
    }
    out->pair = CheckedPair(v[0], num_pairs, where);
    out->T = Transform::Identity();
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) out->T(r, c) = v[static_cast<std::size_t>(1 + 4 * r + c)];
    }
    out->seconds = v.size() == 14 ? v[13] : 0.0;
}

}  // namespace

std::vector<ExternalTransform> ReadTransforms(const std::string& path, std::size_t num_pairs,
                                              const std::string& method, double rigid_tolerance,
                                              bool allow_scale) {
    const bool csv = EndsWith(path, ".csv");
    if (!csv && !EndsWith(path, ".jsonl") && !EndsWith(path, ".json")) {
        throw std::runtime_error(path + ": transforms file must end in .jsonl or .csv");
    }
    RequireRegularFile(path);
    std::ifstream in(path);
    if (!in) throw std::runtime_error(path + ": cannot open transforms file");
    std::vector<ExternalTransform> out;
    std::map<std::size_t, std::string> seen;  // pair -> file:line
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
        } else if (!ParseJsonLine(line, where, num_pairs, method, &t, &other_methods)) {
            continue;
        }
        if (t.content_hash.empty()) t.content_hash = file_hash;
        if (!std::isfinite(t.seconds) || t.seconds < 0) {
            throw std::runtime_error(where + ": seconds must be a finite number >= 0");
        }
        const std::string problem = RigidProblem(t.T, rigid_tolerance, allow_scale, &t.scale);
        if (!problem.empty()) {
            throw std::runtime_error(
                where + ": transform of pair " + std::to_string(t.pair) + " " + problem +
                (allow_scale ? ""
                             : " (scoring needs a rigid transform; --allow-scale accepts s R)"));
        }
        const auto [it, fresh] = seen.emplace(t.pair, where);
        if (!fresh) {
            throw std::runtime_error(where + ": pair " + std::to_string(t.pair) +
                                     " given twice (first at " + it->second + ")");
        }
        out.push_back(t);
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
    context.metric_options = o.metric_options;
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
                "' line (the scored file's hash), or pass --allow-unhashed to score it anyway");
        }
    }
    const std::string scale = PairScaleWarning(set, o.metric_options);
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
