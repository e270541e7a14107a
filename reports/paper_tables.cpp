#include "reports/paper_tables.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <stdexcept>

#include "core/data_dir.hpp"
#include "core/input_file.hpp"
#include "reports/conventions.hpp"
#include "reports/row_access.hpp"

namespace regbench {

nlohmann::json LoadPaperTables(const std::string& path) {
    RequireRegularFile(path);
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

std::optional<std::string> PaperRowName(const PaperRows& rows, const std::string& method) {
    const auto it = rows.find(method);
    if (it == rows.end() || it->second.empty()) return std::nullopt;
    return it->second;
}

namespace {

/// The column groups of a paper table ("same_category" of "same_category.mae_r"), in column
/// order; `plain` is set when it has an ungrouped "mae_r" or "seconds" column.
std::vector<std::string> ColumnGroups(const nlohmann::json& table, bool* plain) {
    std::vector<std::string> groups;
    *plain = false;
    for (const auto& c : table.at("columns")) {
        const std::string name = c.get<std::string>();
        *plain |= name == "mae_r" || name == "seconds";
        const auto dot = name.rfind('.');
        if (dot == std::string::npos || name.substr(dot + 1) != "mae_r") continue;
        const std::string g = name.substr(0, dot);
        if (std::find(groups.begin(), groups.end(), g) == groups.end()) groups.push_back(g);
    }
    return groups;
}

std::string JoinNames(const std::vector<std::string>& names) {
    std::string out;
    for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
    return out;
}

}  // namespace

PaperSelection ResolvePaperSelection(const nlohmann::json& paper, const std::string& text) {
    const auto colon = text.find(':');
    const std::string name = text.substr(0, colon);
    const std::string group = colon == std::string::npos ? "" : text.substr(colon + 1);
    const auto& tables = paper.at("tables");
    std::vector<std::string> known, matching;
    for (const auto& t : tables.items()) {
        known.push_back(t.key());
        if (!name.empty() && t.key().rfind(name, 0) == 0) matching.push_back(t.key());
    }
    if (tables.contains(name)) matching = {name};
    if (matching.empty()) {
        throw std::invalid_argument("--paper " + text + ": '" + name +
                                    "' names no paper table (tables: " + JoinNames(known) + ")");
    }
    if (matching.size() > 1) {
        throw std::invalid_argument("--paper " + text + ": '" + name +
                                    "' names several paper tables (" + JoinNames(matching) +
                                    "): give one");
    }
    PaperSelection sel{matching.front(), group};
    bool plain = false;
    const std::vector<std::string> groups = ColumnGroups(tables.at(sel.table), &plain);
    if (groups.empty() && !plain) {
        throw std::invalid_argument("--paper " + text + ": paper table " + sel.table +
                                    " has no MAE(R) or seconds column to compare with");
    }
    if (groups.empty() && !group.empty()) {
        throw std::invalid_argument("--paper " + text + ": paper table " + sel.table +
                                    " has no column groups; give it as " + sel.table);
    }
    if (!groups.empty() && std::find(groups.begin(), groups.end(), group) == groups.end()) {
        throw std::invalid_argument(
            "--paper " + text + ": paper table " + sel.table +
            (group.empty() ? " needs a column group" : " has no column group '" + group + "'") +
            ", TABLE:GROUP (groups: " + JoinNames(groups) + ")");
    }
    return sel;
}

Table PaperComparisonTable(const ReportTable& ours, const nlohmann::json& paper,
                           const std::string& table, const std::string& group,
                           const PaperRows& paper_rows) {
    const auto& tables = paper.at("tables");
    if (!tables.contains(table)) {
        std::string known;
        for (const auto& t : tables.items()) known += (known.empty() ? "" : ", ") + t.key();
        throw std::invalid_argument("unknown paper table '" + table + "' (known: " + known + ")");
    }
    const auto& pt = tables.at(table);
    const auto& columns = pt.at("columns");
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
    const auto& time_rows = tables.value("table6_inference_time", nlohmann::json::object());
    const auto paper_cell = [&](const std::optional<std::string>& row, const std::string& metric) {
        Cell c;
        c.source = CellSource::kPaper;
        if (!row) return c;
        if (metric == "seconds") {  // Tab. 6's one column
            if (time_rows.contains("rows") && time_rows["rows"].contains(*row))
                c.value = time_rows["rows"][*row].at(0).get<double>();
            return c;
        }
        const int i = column_index(metric);
        if (i >= 0 && pt.at("rows").contains(*row))
            c.value = pt.at("rows").at(*row).at(static_cast<std::size_t>(i)).get<double>();
        return c;
    };
    Table t;
    t.id = "paper:" + table + (group.empty() ? "" : ":" + group);
    t.caption = fmt::format("Paper: {} ({}){}", table, pt.value("caption", ""),
                            group.empty() ? "" : ", columns " + group);
    t.caption += "\n" + PaperTableConventions(ours.rows);
    const auto measured = [](const std::string& key, int decimals) {
        return Column{key, key, CellSource::kMeasured, Better::kNone, decimals};
    };
    const auto published = [](const std::string& key, int decimals) {
        return Column{"paper:" + key, "paper " + key, CellSource::kPaper, Better::kNone, decimals};
    };
    t.columns = {measured("pairs", 0)};
    for (const char* m : {"mae_r", "mae_t", "ccd"}) {
        t.columns.push_back(measured(m, FindMetric(m).decimals));
        t.columns.push_back(published(m, FindMetric(m).decimals));
    }
    t.columns.push_back(measured("median s", kSecondsDecimals));
    t.columns.back().key = "median_seconds";
    t.columns.push_back(published("s", kSecondsDecimals));
    t.columns.back().key = "paper:seconds";
    for (const auto& s : ours.methods) {
        const auto row = PaperRowName(paper_rows, s.method);
        const auto mine = [&](double v) { return MeasuredCell(v, s.pairs); };
        const auto mean = [&](const Estimate& e) {  // with its bootstrap CI
            Cell c = mine(e.mean);
            c.ci_lo = e.lo;
            c.ci_hi = e.hi;
            return c;
        };
        t.AddRow(s.method, {{"pairs", mine(static_cast<double>(s.pairs))},
                            {"mae_r", mean(s.mae_r)},
                            {"paper:mae_r", paper_cell(row, "mae_r")},
                            {"mae_t", mean(s.mae_t)},
                            {"paper:mae_t", paper_cell(row, "mae_t")},
                            {"ccd", mean(s.ccd)},
                            {"paper:ccd", paper_cell(row, "ccd")},
                            {"median_seconds", mine(s.median_seconds)},
                            {"paper:seconds", paper_cell(row, "seconds")}});
    }
    t.notes.push_back("Ours: " + DescribeTable(ours) +
                      ". Paper: ModelNet40 / 7Scenes / ICL-NUIM as published (their machine, their "
                      "pairs; mae_r with scipy as_euler('zyx')).");
    return t;
}

}  // namespace regbench
