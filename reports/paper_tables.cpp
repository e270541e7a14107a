#include "reports/paper_tables.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <fstream>
#include <stdexcept>

#include "core/data_dir.hpp"

namespace regbench {

nlohmann::json LoadPaperTables(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error(path + ": cannot open the paper's tables");
    try {
        // Parsed order-preserving once to record each table's row order ("row_order"): the
        // plain json type sorts object keys, and tables must list rows as the paper does.
        const nlohmann::ordered_json ordered = nlohmann::ordered_json::parse(in);
        nlohmann::json j = nlohmann::json::parse(ordered.dump());
        if (!j.contains("tables")) throw std::runtime_error("no 'tables' key");
        for (const auto& t : ordered.at("tables").items()) {
            if (!t.value().contains("rows")) continue;
            std::vector<std::string> order;
            for (const auto& r : t.value().at("rows").items()) order.push_back(r.key());
            j["tables"][t.key()]["row_order"] = order;
        }
        return j;
    } catch (const std::exception& e) {
        throw std::runtime_error(path + ": malformed paper tables: " + e.what());
    }
}

std::string DefaultPaperTablesPath() { return DataDir() + "/paper/ogmm_wacv2023_tables.json"; }

std::optional<std::string> PaperRowName(const std::string& method) {
    static const std::map<std::string, std::string> kNames = {
        {"icp", "ICP"},         {"fgr", "FGR"},  {"cpd", "CPD"},
        {"gmmreg", "GMMReg"},   {"svr", "SVR"},  {"filterreg", "FilterReg"},
        {"deepgmr", "DeepGMR"}, {"ogmm", "OGMM"}};
    const auto it = kNames.find(method);
    if (it == kNames.end()) return std::nullopt;
    return it->second;
}

std::string FormatPaperComparison(const std::vector<MethodSummary>& ours,
                                  const nlohmann::json& paper,
                                  const std::string& table,
                                  const std::string& group) {
    const auto& tables = paper.at("tables");
    if (!tables.contains(table)) {
        std::string known;
        for (const auto& t : tables.items()) known += (known.empty() ? "" : ", ") + t.key();
        throw std::invalid_argument("unknown paper table '" + table + "' (known: " + known + ")");
    }
    const auto& t = tables.at(table);
    const auto& columns = t.at("columns");
    const std::string prefix = group.empty() ? "" : group + ".";
    auto column_index = [&](const std::string& metric) -> int {
        for (std::size_t i = 0; i < columns.size(); ++i) {
            if (columns[i].get<std::string>() == prefix + metric) return static_cast<int>(i);
        }
        return -1;
    };
    if (column_index("mae_r") < 0 && column_index("seconds") < 0) {
        std::string known;
        for (const auto& c : columns) known += (known.empty() ? "" : ", ") + c.get<std::string>();
        throw std::invalid_argument("paper table '" + table + "' has no column group '" + group +
                                    "' (columns: " + known + ")");
    }
    const auto cell = [&](const std::string& row, const std::string& metric) -> std::string {
        const int c = column_index(metric);
        if (c < 0 || !t.at("rows").contains(row)) return "-";
        return fmt::format("{:g}",
                           t.at("rows").at(row).at(static_cast<std::size_t>(c)).get<double>());
    };
    std::string out = fmt::format("Paper: {} ({}){}\n\n", table, t.value("caption", ""),
                                  group.empty() ? "" : ", columns " + group);
    out +=
        "| method | mae_r | paper mae_r | mae_t | paper mae_t | ccd | paper ccd | median s | paper "
        "s |\n";
    out += "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    const auto& time_rows =
        paper.at("tables").value("table6_inference_time", nlohmann::json::object());
    for (const auto& s : ours) {
        const auto row = PaperRowName(s.method);
        const std::string name = row.value_or("");
        std::string paper_s = "-";
        if (row && time_rows.contains("rows") && time_rows["rows"].contains(name)) {
            paper_s = fmt::format("{:g}", time_rows["rows"][name].at(0).get<double>());
        }
        out += fmt::format("| {} | {:.4f} | {} | {:.4f} | {} | {:.4f} | {} | {:.5f} | {} |\n",
                           s.method, s.mae_r.mean, row ? cell(name, "mae_r") : "-", s.mae_t.mean,
                           row ? cell(name, "mae_t") : "-", s.ccd.mean,
                           row ? cell(name, "ccd") : "-", s.median_seconds, paper_s);
    }
    return out;
}

}  // namespace regbench
