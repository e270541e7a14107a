#include "runners/resume.hpp"

#include <cstdint>
#include <fstream>
#include <set>
#include <stdexcept>
#include <utility>

namespace regbench {
namespace {

[[noreturn]] void Refuse(const std::string& where, const std::string& what) {
    throw std::runtime_error(where + ": " + what);
}

bool IsMatrix4(const nlohmann::json& t) {
    if (!t.is_array() || t.size() != 4) return false;
    for (const auto& row : t) {
        if (!row.is_array() || row.size() != 4) return false;
        for (const auto& v : row) {
            if (!v.is_number() && !v.is_null()) return false;
        }
    }
    return true;
}

/// Field name -> a check of its JSON type; the fields every result row carries.
void CheckRequiredFields(const nlohmann::json& row, const std::string& where) {
    using Check = bool (*)(const nlohmann::json&);
    static const std::pair<const char*, Check> kFields[] = {
        {"pair", [](const nlohmann::json& j) { return j.is_number_unsigned(); }},
        {"method", [](const nlohmann::json& j) { return j.is_string(); }},
        {"params", [](const nlohmann::json& j) { return j.is_object(); }},
        {"transform", [](const nlohmann::json& j) { return IsMatrix4(j); }},
        {"seconds", [](const nlohmann::json& j) { return j.is_number(); }},
        {"iterations", [](const nlohmann::json& j) { return j.is_number_integer(); }},
        {"stop_reason", [](const nlohmann::json& j) { return j.is_string(); }},
        {"status", [](const nlohmann::json& j) { return j.is_string(); }},
        {"message", [](const nlohmann::json& j) { return j.is_string(); }},
        {"metrics", [](const nlohmann::json& j) { return j.is_object(); }},
        {"data", [](const nlohmann::json& j) { return j.is_object(); }},
    };
    if (!row.is_object()) Refuse(where, "not a JSON object");
    for (const auto& [name, check] : kFields) {
        if (!row.contains(name)) Refuse(where, std::string("missing field '") + name + "'");
        if (!check(row.at(name)))
            Refuse(where, std::string("field '") + name + "' has the wrong type");
    }
}

}  // namespace

ResultRow CheckResultRow(const nlohmann::json& json, const RowExpectation& expect,
                         const std::string& where) {
    CheckRequiredFields(json, where);
    ResultRow row;
    try {
        row = json.get<ResultRow>();   // types every field; an unknown status is refused here
        CheckRowAsWritten(json, row);  // values a writer can give (null, -1, 1e308 refused)
    } catch (const std::exception& e) {
        Refuse(where, std::string("not a result row: ") + e.what());
    }
    row.origin = where;
    // "missing" is what `score` writes for an absent transform; a run never writes it.
    if (row.status == Status::kMissing) Refuse(where, "status 'missing' is not a run's status");
    if (row.pair >= expect.num_pairs) {
        Refuse(where, "pair " + std::to_string(row.pair) + " is not in the pair file (" +
                          std::to_string(expect.num_pairs) + " pairs)");
    }
    if (static_cast<int>(row.pair % static_cast<std::size_t>(expect.shard_count)) !=
        expect.shard_index) {
        Refuse(where, "pair " + std::to_string(row.pair) + " belongs to another shard");
    }
    const MethodSpec* spec = nullptr;
    for (const auto& m : expect.methods) {
        if (m.name == row.method) spec = &m;
    }
    if (spec == nullptr) Refuse(where, "method '" + row.method + "' is not in --methods");
    if (row.params != spec->params) {
        Refuse(where, "method '" + row.method + "' ran with other parameters " + row.params.dump() +
                          " (this run: " + spec->params.dump() + ")");
    }
    if (row.metrics.ccd_clip != expect.metric_options.ccd_clip ||
        row.metrics.inlier_threshold != expect.metric_options.inlier_threshold) {
        Refuse(where, "row was measured with --ccd-clip " + std::to_string(row.metrics.ccd_clip) +
                          " --inlier-threshold " + std::to_string(row.metrics.inlier_threshold) +
                          ", this run with " + std::to_string(expect.metric_options.ccd_clip) +
                          " and " + std::to_string(expect.metric_options.inlier_threshold));
    }
    if (row.data.content_hash != expect.content_hash) {
        Refuse(where, "row comes from other pair data (content_hash '" + row.data.content_hash +
                          "', this run '" + expect.content_hash + "')");
    }
    return row;
}

std::vector<ResultRow> ReadResumableRows(const std::string& path, const RowExpectation& expect) {
    std::vector<ResultRow> rows;
    std::set<std::pair<std::size_t, std::string>> seen;
    // A torn last line is the write a kill cut short: it is redone.
    ForEachJsonlLine(path, TornLastLine::kSkip,
                     [&](const std::string& where, const nlohmann::json& row) {
                         ResultRow typed = CheckResultRow(row, expect, where);
                         const auto key = std::make_pair(typed.pair, typed.method);
                         if (!seen.insert(key).second) {
                             Refuse(where, "duplicate row for pair " + std::to_string(key.first) +
                                               ", method '" + key.second + "'");
                         }
                         rows.push_back(std::move(typed));
                     });
    return rows;
}

}  // namespace regbench
