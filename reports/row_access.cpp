#include "reports/row_access.hpp"

#include <cmath>
#include <stdexcept>

namespace regbench {

namespace {
const MetricField kMetrics[] = {{"mae_r", &PairMetrics::mae_r, 4},
                                {"mae_t", &PairMetrics::mae_t, 4},
                                {"mse_r", &PairMetrics::mse_r, 4},
                                {"mse_t", &PairMetrics::mse_t, 4},
                                {"rre", &PairMetrics::rre, 4},
                                {"rte", &PairMetrics::rte, 4},
                                {"ccd", &PairMetrics::ccd, 4},
                                {"chamfer", &PairMetrics::chamfer, 4},
                                {"overlap_rmse", &PairMetrics::overlap_rmse, 4}};
}  // namespace

std::vector<std::string> MetricNames() {
    std::vector<std::string> names;
    for (const auto& m : kMetrics) names.push_back(m.name);
    return names;
}

const MetricField& FindMetric(const std::string& name) {
    std::string known;
    for (const auto& m : kMetrics) {
        if (name == m.name) return m;
        known += (known.empty() ? "" : ", ") + std::string(m.name);
    }
    throw std::invalid_argument("unknown metric '" + name + "' (known: " + known + ")");
}

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
    const auto v = m->find(FindMetric(key).name);
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
