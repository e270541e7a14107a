#include "reports/row_access.hpp"

#include <cmath>

namespace regbench {

std::string RowPairFileName(const nlohmann::json& row) {
    if (!row.contains("data") || !row["data"].is_object()) return "?";
    return row["data"].value("pairs_file", std::string("?"));
}

std::string RowPairFileId(const nlohmann::json& row) {
    if (row.contains("data") && row["data"].is_object()) {
        for (const char* key : {"content_hash", "pairs_hash", "hash"}) {
            const auto it = row["data"].find(key);
            if (it != row["data"].end() && it->is_string() && !it->get<std::string>().empty())
                return it->get<std::string>();
        }
    }
    return "file:" + RowPairFileName(row);
}

std::optional<double> RowMetric(const nlohmann::json& row, const std::string& key) {
    const auto m = row.find("metrics");
    if (m == row.end() || !m->is_object()) return std::nullopt;
    const auto v = m->find(key);
    if (v == m->end() || !v->is_number()) return std::nullopt;
    const double x = v->get<double>();
    if (!std::isfinite(x)) return std::nullopt;
    return x;
}

std::string RowStatus(const nlohmann::json& row) {
    const auto s = row.find("status");
    return s != row.end() && s->is_string() ? s->get<std::string>() : "failed";
}

std::optional<double> RowOverlap(const nlohmann::json& row, const char* which) {
    const std::string key = std::string(which) + "_overlap_ratio";
    for (const nlohmann::json* obj : {&row, row.contains("data") ? &row["data"] : nullptr}) {
        if (obj == nullptr || !obj->is_object()) continue;
        const auto v = obj->find(key);
        if (v != obj->end() && v->is_number()) return v->get<double>();
    }
    return std::nullopt;
}

}  // namespace regbench
