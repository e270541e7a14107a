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

PaperComparison BuildPaperComparison(const std::vector<MethodSummary>& ours,
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
    const auto cell = [&](const std::optional<std::string>& row,
                          const std::string& metric) -> std::optional<double> {
        const int c = column_index(metric);
        if (!row || c < 0 || !t.at("rows").contains(*row)) return std::nullopt;
        return t.at("rows").at(*row).at(static_cast<std::size_t>(c)).get<double>();
    };
    PaperComparison out;
    out.table = table;
    out.group = group;
    out.caption = t.value("caption", "");
    const auto& time_rows =
        paper.at("tables").value("table6_inference_time", nlohmann::json::object());
    for (const auto& s : ours) {
        PaperComparisonRow r;
        r.method = s.method;
        r.pairs = s.pairs;
        r.mae_r = s.mae_r.mean;
        r.mae_t = s.mae_t.mean;
        r.ccd = s.ccd.mean;
        r.median_seconds = s.median_seconds;
        const auto row = PaperRowName(s.method);
        r.paper_row = row.value_or("");
        r.paper_mae_r = cell(row, "mae_r");
        r.paper_mae_t = cell(row, "mae_t");
        r.paper_ccd = cell(row, "ccd");
        if (row && time_rows.contains("rows") && time_rows["rows"].contains(*row)) {
            r.paper_seconds = time_rows["rows"][*row].at(0).get<double>();
        }
        out.rows.push_back(std::move(r));
    }
    return out;
}

namespace {
std::string Cell(const std::optional<double>& v) {
    return v ? fmt::format("{:g}", *v) : std::string("-");
}
/// An absent paper cell is an empty CSV field ("-" is no number).
std::string CsvCell(const std::optional<double>& v) {
    return v ? fmt::format("{:g}", *v) : std::string();
}
nlohmann::json JsonCell(const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}
std::string CsvQuote(const std::string& s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string q = "\"";
    for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
}
std::string LatexEscape(const std::string& s) {
    std::string out;
    for (const char c : s) {
        if (c == '_' || c == '&' || c == '%' || c == '#' || c == '$') out += '\\';
        out += c;
    }
    return out;
}
}  // namespace

std::string FormatPaperComparison(const PaperComparison& c, const std::string& format) {
    if (format == "csv") {
        std::string out =
            "paper_table,paper_group,method,pairs,mae_r,paper_mae_r,mae_t,paper_mae_t,ccd,"
            "paper_ccd,median_seconds,paper_seconds\n";
        for (const auto& r : c.rows) {
            out += fmt::format("{},{},{},{},{:.6g},{},{:.6g},{},{:.6g},{},{:.6g},{}\n",
                               CsvQuote(c.table), CsvQuote(c.group), CsvQuote(r.method), r.pairs,
                               r.mae_r, CsvCell(r.paper_mae_r), r.mae_t, CsvCell(r.paper_mae_t),
                               r.ccd, CsvCell(r.paper_ccd), r.median_seconds,
                               CsvCell(r.paper_seconds));
        }
        return out;
    }
    if (format == "json") return ToJson(c).dump(2) + "\n";
    if (format == "latex") {
        std::string out = "\\begin{table}\n\\centering\n\\caption{" +
                          LatexEscape("Ours beside the paper: " + c.table +
                                      (c.group.empty() ? "" : ", columns " + c.group)) +
                          "}\n\\begin{tabular}{lrrrrrrrrr}\n\\toprule\n"
                          "method & pairs & MAE(R) & paper & MAE(t) & paper & CCD & paper & "
                          "median s & paper s \\\\\n\\midrule\n";
        for (const auto& r : c.rows) {
            out += fmt::format("{} & {} & {:.4f} & {} & {:.4f} & {} & {:.4f} & {} & {:.5f} & {} "
                               "\\\\\n",
                               LatexEscape(r.method), r.pairs, r.mae_r, Cell(r.paper_mae_r),
                               r.mae_t, Cell(r.paper_mae_t), r.ccd, Cell(r.paper_ccd),
                               r.median_seconds, Cell(r.paper_seconds));
        }
        return out + "\\bottomrule\n\\end{tabular}\n\\end{table}\n";
    }
    std::string out = fmt::format("Paper: {} ({}){}\n\n", c.table, c.caption,
                                  c.group.empty() ? "" : ", columns " + c.group);
    out +=
        "| method | pairs | mae_r | paper mae_r | mae_t | paper mae_t | ccd | paper ccd | "
        "median s | paper s |\n";
    out += "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const auto& r : c.rows) {
        out += fmt::format("| {} | {} | {:.4f} | {} | {:.4f} | {} | {:.4f} | {} | {:.5f} | {} |\n",
                           r.method, r.pairs, r.mae_r, Cell(r.paper_mae_r), r.mae_t,
                           Cell(r.paper_mae_t), r.ccd, Cell(r.paper_ccd), r.median_seconds,
                           Cell(r.paper_seconds));
    }
    return out;
}

nlohmann::json ToJson(const PaperComparison& c) {
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& r : c.rows) {
        rows.push_back({{"method", r.method},
                        {"paper_row", r.paper_row},
                        {"pairs", r.pairs},
                        {"mae_r", r.mae_r},
                        {"paper_mae_r", JsonCell(r.paper_mae_r)},
                        {"mae_t", r.mae_t},
                        {"paper_mae_t", JsonCell(r.paper_mae_t)},
                        {"ccd", r.ccd},
                        {"paper_ccd", JsonCell(r.paper_ccd)},
                        {"median_seconds", r.median_seconds},
                        {"paper_seconds", JsonCell(r.paper_seconds)}});
    }
    return {{"table", c.table}, {"group", c.group}, {"caption", c.caption}, {"rows", rows}};
}

std::string FormatPaperComparison(const std::vector<MethodSummary>& ours,
                                  const nlohmann::json& paper,
                                  const std::string& table,
                                  const std::string& group) {
    return FormatPaperComparison(BuildPaperComparison(ours, paper, table, group), "md");
}

}  // namespace regbench
