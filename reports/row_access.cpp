#include "reports/row_access.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

namespace regbench {

std::vector<std::string> MetricNames() {
    std::vector<std::string> names;
    for (const auto& m : PerPairMetrics()) names.push_back(m.name);
    return names;
}

const MetricField& FindMetric(const std::string& name) {
    std::string known;
    for (const auto& m : PerPairMetrics()) {
        if (name == m.name) return m;
        known += (known.empty() ? "" : ", ") + std::string(m.name);
    }
    throw std::invalid_argument("unknown metric '" + name + "' (known: " + known + ")");
}

std::string RowPairFileId(const ResultRow& row) {
    if (!row.data.content_hash.empty()) return row.data.content_hash;
    return "file:" + row.data.pairs_file;
}

std::optional<double> MeasuredOverlap(const ResultRow& row) {
    if (!row.source_overlap_ratio || !row.target_overlap_ratio) return std::nullopt;
    return std::min(*row.source_overlap_ratio, *row.target_overlap_ratio);
}

std::vector<std::string> MethodOrder(const std::vector<ResultRow>& rows) {
    std::vector<std::string> order;
    std::set<std::string> seen;
    for (const auto& r : rows) {
        if (seen.insert(r.method).second) order.push_back(r.method);
    }
    return order;
}

std::vector<const ResultRow*> RowsOf(const std::vector<ResultRow>& rows,
                                     const std::string& method) {
    std::vector<const ResultRow*> out;
    for (const auto& r : rows) {
        if (r.method == method) out.push_back(&r);
    }
    return out;
}

}  // namespace regbench
