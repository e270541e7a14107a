#include <fmt/format.h>

#include <algorithm>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/enum_names.hpp"
#include "reports/table.hpp"

namespace regbench {
namespace {

constexpr EnumName<CellSource> kSourceNames[] = {
    {CellSource::kLabel, "label"},
    {CellSource::kMeasured, "measured"},
    {CellSource::kPaper, "paper"},
};

const char* SourceName(CellSource s) { return EnumToString(kSourceNames, s); }

/// The provenance entry a column's cells came from: the one whose group prefixes the key.
const Provenance* ProvenanceFor(const Table& t, const Column& col) {
    if (col.source != CellSource::kMeasured) return nullptr;
    const std::string group = col.key.substr(0, col.key.find('.'));
    for (const auto& p : t.provenance) {
        if (!p.group.empty() && p.group == group) return &p;
    }
    return t.provenance.size() == 1 ? &t.provenance.front() : nullptr;
}

std::string LatexEscape(const std::string& s) {
    std::string out;
    for (char c : s) {
        switch (c) {
            case '_':
            case '%':
            case '&':
            case '#':
            case '$':
            case '{':
            case '}':
                out += '\\';
                out += c;
                break;
            case '~':
                out += "\\textasciitilde{}";
                break;
            case '^':
                out += "\\textasciicircum{}";
                break;
            case '\\':
                out += "\\textbackslash{}";
                break;
            case '<':
                out += "\\textless{}";
                break;
            case '>':
                out += "\\textgreater{}";
                break;
            default:
                out += c;
        }
    }
    return out;
}

std::string CsvField(const std::string& s) {
    if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
    std::string q = "\"";
    for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
}

std::string Num(double v) { return std::isfinite(v) ? fmt::format("{:.10g}", v) : ""; }

// clang-format off
const std::vector<std::string> kCsvHeader = {
    "table",      "row",          "column",    "header",   "source",    "value",
    "ci95_half_width", "ci95_lo", "ci95_hi",   "text",     "pairs",     "pairs_file",
    "pairs_hash", "dataset",      "split",     "protocol", "pairing",   "seed",
    "points",     "keep",         "regbench_version", "fallback", "gt_ccd_floor", "selection",
    "noise_sigma", "weights"};
// clang-format on

}  // namespace

const Cell& TableRow::Get(const std::string& key) const {
    static const Cell kEmpty;
    const auto it = cells_.find(key);
    return it == cells_.end() ? kEmpty : it->second;
}

std::size_t Table::ColumnIndex(const std::string& key) const {
    for (std::size_t c = 0; c < columns.size(); ++c) {
        if (columns[c].key == key) return c;
    }
    throw std::logic_error(fmt::format("table '{}' has no column '{}'", id, key));
}

TableRow& Table::AddRow(std::string label, const RowCells& cells) {
    std::set<std::string> keys;
    for (const auto& c : columns) {
        if (!keys.insert(c.key).second) {
            throw std::logic_error(fmt::format("table '{}' has two columns '{}'", id, c.key));
        }
    }
    TableRow row(std::move(label));
    for (const auto& [key, cell] : cells) {
        if (!keys.count(key)) {
            throw std::logic_error(fmt::format("table '{}', row '{}': no column '{}' for its cell",
                                               id, row.label, key));
        }
        if (!row.cells_.emplace(key, cell).second) {
            throw std::logic_error(
                fmt::format("table '{}', row '{}': two cells for column '{}'", id, row.label, key));
        }
    }
    rows.push_back(std::move(row));
    return rows.back();
}

namespace {

/// Decimals of a compact cell, at most the column's: the CI's half-width to two significant
/// digits; without a CI (or with a zero-width one) the value to three (0.00539 s, 21.1 deg).
int CompactDecimals(const Cell& c, const Column& col) {
    // A rate (fraction of pairs) at percent resolution: its Wilson interval is wide anyway.
    if (col.ci == CiStyle::kValueInterval) return std::min(2, col.decimals);
    const double hw = c.HalfWidth();
    const bool ci = std::isfinite(hw) && hw > 0.0;
    const double v = ci ? hw : std::abs(c.value);
    if (!std::isfinite(v) || v <= 0.0) return col.decimals;
    const int d = (ci ? 1 : 2) - static_cast<int>(std::floor(std::log10(v)));
    return std::clamp(d, 0, col.decimals);
}

}  // namespace

std::string CellText(const Cell& c, const Column& col, const char* pm, TableForm form) {
    if (!c.text.empty()) return c.text;
    if (!c.HasValue()) return "-";
    const bool ci = std::isfinite(c.ci_lo) && std::isfinite(c.ci_hi);
    const int d = form == TableForm::kCompact ? CompactDecimals(c, col) : col.decimals;
    if (col.ci == CiStyle::kInterval) {
        return ci ? fmt::format("[{:.{}f}, {:.{}f}]", c.ci_lo, d, c.ci_hi, d) : "-";
    }
    if (form == TableForm::kCompact && col.source == CellSource::kPaper) {
        return fmt::format("{}", c.value);  // as transcribed: shortest round-trip digits
    }
    std::string s = fmt::format("{:.{}f}", c.value, d);
    if (ci && col.ci == CiStyle::kPlusMinus) s += fmt::format("{}{:.{}f}", pm, c.HalfWidth(), d);
    if (ci && col.ci == CiStyle::kValueInterval) {
        s += fmt::format(" [{:.{}f}, {:.{}f}]", c.ci_lo, d, c.ci_hi, d);
    }
    return s;
}

namespace {

/// The entry of t.column_groups that column `key` is in, "" for none.
std::string ColumnGroup(const Table& t, std::string key) {
    if (key.rfind("paper:", 0) == 0) key.erase(0, 6);
    for (const auto& g : t.column_groups) {
        if (key.rfind(g + ".", 0) == 0) return g;
    }
    return "";
}

}  // namespace

ShownTable ShowTable(const Table& t, TableForm form, const char* pm) {
    const bool compact = form == TableForm::kCompact;
    // Per shown column: the table's column and (compact) the paper column merged into it.
    std::vector<std::pair<std::size_t, int>> shown;
    for (std::size_t c = 0; c < t.columns.size(); ++c) {
        const Column& col = t.columns[c];
        if (!col.shown || (compact && !col.compact)) continue;
        const bool merge = compact && col.source == CellSource::kPaper && !shown.empty() &&
                           col.key == "paper:" + t.columns[shown.back().first].key;
        if (merge) {
            shown.back().second = static_cast<int>(c);
        } else {
            shown.emplace_back(c, -1);
        }
    }
    ShownTable out;
    for (const auto& [c, paper] : shown) {
        const Column& col = t.columns[c];
        out.columns.push_back({col.header + (paper >= 0 ? " (paper)" : ""),
                               col.ci == CiStyle::kInterval, col.source == CellSource::kPaper,
                               ColumnGroup(t, col.key), paper >= 0});
    }
    std::vector<int> best(t.columns.size());
    for (std::size_t c = 0; c < t.columns.size(); ++c) best[c] = BestRow(t, c);
    for (std::size_t r = 0; r < t.rows.size(); ++r) {
        out.labels.push_back(t.rows[r].label);
        out.cells.emplace_back();
        out.best.emplace_back();
        for (const auto& [c, paper] : shown) {
            const Column& col = t.columns[c];
            std::string s = CellText(t.rows[r].Get(col.key), col, pm, form);
            if (paper >= 0) {
                const Column& pc = t.columns[static_cast<std::size_t>(paper)];
                const Cell& p = t.rows[r].Get(pc.key);
                if (p.HasValue() || !p.text.empty()) s += " (" + CellText(p, pc, pm, form) + ")";
            }
            out.cells.back().push_back(s);
            out.best.back().push_back(best[c] == static_cast<int>(r));
        }
    }
    return out;
}

int BestRow(const Table& t, std::size_t c) {
    const Column& col = t.columns.at(c);
    if (col.better == Better::kNone || col.source != CellSource::kMeasured) return -1;
    int best = -1;
    for (std::size_t r = 0; r < t.rows.size(); ++r) {
        const Cell& cell = t.rows[r].Get(col.key);
        if (!cell.HasValue() || !cell.text.empty()) continue;
        const double v = cell.value;
        if (best < 0) {
            best = static_cast<int>(r);
            continue;
        }
        const double b = t.rows[static_cast<std::size_t>(best)].Get(col.key).value;
        if ((col.better == Better::kLower && v < b) || (col.better == Better::kHigher && v > b)) {
            best = static_cast<int>(r);
        }
    }
    return best;
}

std::vector<std::string> DataSources(const Table& t) {
    std::vector<std::string> out;
    for (const auto& p : t.provenance) {
        if (!p.fallback.empty() && std::find(out.begin(), out.end(), p.fallback) == out.end())
            out.push_back(p.fallback);
    }
    return out;
}

namespace {

/// The widest line a compact Markdown table may take: a 120-column terminal or editor.
constexpr std::size_t kMarkdownWidth = 120;

/// The Markdown grid (header, rule, rows) of the shown columns `cols`; a header naming
/// `group` loses the name (the grid's heading says it instead).
std::string MarkdownGrid(const ShownTable& s, const std::string& row_header,
                         const std::vector<std::size_t>& cols, const std::string& group) {
    std::string out = "| " + row_header + " |";
    std::string rule = "|---|";
    for (const std::size_t c : cols) {
        std::string header = s.columns[c].header;
        if (const auto at = header.find(" " + group); !group.empty() && at != std::string::npos)
            header.erase(at, group.size() + 1);
        out += " " + header + " |";
        rule += s.columns[c].left ? "---|" : "---:|";
    }
    out += "\n" + rule + "\n";
    for (std::size_t r = 0; r < s.labels.size(); ++r) {
        out += "| " + s.labels[r] + " |";
        for (const std::size_t c : cols)
            out += " " + (s.best[r][c] ? "**" + s.cells[r][c] + "**" : s.cells[r][c]) + " |";
        out += "\n";
    }
    return out;
}

std::size_t LongestLine(const std::string& text) {
    std::size_t longest = 0;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) longest = std::max(longest, line.size());
    return longest;
}

/// Compact and wider than kMarkdownWidth with two or more column groups: one grid per group,
/// under the group's name (ungrouped columns in each); otherwise the one grid.
std::string MarkdownGrids(const ShownTable& s, const std::string& row_header, TableForm form) {
    std::vector<std::size_t> all(s.columns.size());
    for (std::size_t c = 0; c < all.size(); ++c) all[c] = c;
    const std::string whole = MarkdownGrid(s, row_header, all, "");
    std::vector<std::string> groups;
    for (const auto& c : s.columns) {
        if (!c.group.empty() && std::find(groups.begin(), groups.end(), c.group) == groups.end())
            groups.push_back(c.group);
    }
    if (form != TableForm::kCompact || groups.size() < 2 || LongestLine(whole) <= kMarkdownWidth)
        return whole;
    std::string out;
    for (const auto& g : groups) {
        std::vector<std::size_t> cols;
        for (const std::size_t c : all) {
            if (s.columns[c].group.empty() || s.columns[c].group == g) cols.push_back(c);
        }
        out += (out.empty() ? "" : "\n") + ("*" + g + "*\n\n") + MarkdownGrid(s, row_header, cols, g);
    }
    return out;
}

}  // namespace

std::string TableToMarkdown(const Table& t, TableForm form) {
    std::string out = t.title.empty() ? "" : "### " + t.title + "\n\n";
    if (!t.caption.empty()) out += t.caption + "\n\n";
    for (const auto& src : DataSources(t)) out += "**Data source: " + src + "**\n\n";
    // Compact: "1.2±0.3", the paper's way, two characters a cell narrower than " ± ".
    const ShownTable s = ShowTable(t, form, form == TableForm::kCompact ? "±" : " ± ");
    out += MarkdownGrids(s, t.row_header, form);
    for (const auto& n : t.notes) out += "\n" + n + "\n";
    return out;
}

std::string TableToLatex(const Table& t) {
    std::string out = "\\begin{table}[t]\n\\centering\n\\small\n\\begin{tabular}{l";
    for (const auto& c : t.columns) out += c.shown ? "r" : "";
    out += "}\n\\toprule\n" + LatexEscape(t.row_header);
    for (const auto& c : t.columns) out += c.shown ? " & " + LatexEscape(c.header) : "";
    out += " \\\\\n\\midrule\n";
    std::vector<int> best(t.columns.size());
    for (std::size_t c = 0; c < t.columns.size(); ++c) best[c] = BestRow(t, c);
    for (std::size_t r = 0; r < t.rows.size(); ++r) {
        out += LatexEscape(t.rows[r].label);
        for (std::size_t c = 0; c < t.columns.size(); ++c) {
            if (!t.columns[c].shown) continue;
            const Cell& cell = t.rows[r].Get(t.columns[c].key);
            std::string s = cell.text.empty() ? CellText(cell, t.columns[c], " $\\pm$ ")
                                              : LatexEscape(cell.text);
            if (best[c] == static_cast<int>(r)) s = "\\textbf{" + s + "}";
            out += " & " + s;
        }
        out += " \\\\\n";
    }
    out += "\\bottomrule\n\\end{tabular}\n";
    const std::string caption =
        t.title.empty() || t.caption.empty() ? t.title + t.caption : t.title + ". " + t.caption;
    out += "\\caption{" + LatexEscape(caption) + "}\n";
    out += "\\label{tab:" + LatexEscape(t.id) + "}\n\\end{table}\n";
    return out;
}

std::string TablesToMarkdown(const std::vector<Table>& tables, TableForm form) {
    std::string out;
    for (std::size_t i = 0; i < tables.size(); ++i)
        out += (i ? "\n" : "") + TableToMarkdown(tables[i], form);
    return out;
}

std::string TablesToCsv(const std::vector<Table>& tables) {
    std::string out;
    for (std::size_t i = 0; i < kCsvHeader.size(); ++i) out += (i ? "," : "") + kCsvHeader[i];
    out += "\n";
    for (const auto& row : TablesToJson(tables)) {
        std::string line;
        for (std::size_t i = 0; i < kCsvHeader.size(); ++i) {
            const auto& v = row.at(kCsvHeader[i]);
            std::string s;
            if (v.is_string()) {
                s = v.get<std::string>();
            } else if (v.is_number_float()) {
                s = Num(v.get<double>());
            } else if (!v.is_null()) {
                s = v.dump();
            }
            line += (i ? "," : "") + CsvField(s);
        }
        out += line + "\n";
    }
    return out;
}

nlohmann::json TablesToJson(const std::vector<Table>& tables) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& t : tables) {
        for (const auto& row : t.rows) {
            for (std::size_t c = 0; c < t.columns.size(); ++c) {
                const Column& col = t.columns[c];
                const Cell& cell = row.Get(col.key);
                const Provenance* p = ProvenanceFor(t, col);
                const auto num = [](double v) -> nlohmann::json {
                    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
                };
                nlohmann::json rec = {{"table", t.id},
                                      {"row", row.label},
                                      {"column", col.key},
                                      {"header", col.header},
                                      {"source", SourceName(col.source)},
                                      {"value", num(cell.value)},
                                      {"ci95_half_width", num(cell.HalfWidth())},
                                      {"ci95_lo", num(cell.ci_lo)},
                                      {"ci95_hi", num(cell.ci_hi)},
                                      {"text", cell.text},
                                      {"pairs", cell.pairs},
                                      {"pairs_file", p ? p->pairs_file : ""},
                                      {"pairs_hash", p ? p->pairs_hash : ""},
                                      {"dataset", p ? p->dataset : ""},
                                      {"split", p ? p->split : ""},
                                      {"protocol", p ? p->protocol : ""},
                                      {"pairing", p ? p->pairing : ""},
                                      {"seed", p ? p->seed : nlohmann::json()},
                                      {"points", p ? p->points : 0},
                                      {"keep", p ? num(p->keep) : nlohmann::json()},
                                      {"regbench_version", p ? p->version : ""},
                                      {"fallback", p ? p->fallback : ""},
                                      {"gt_ccd_floor", p ? num(p->gt_ccd_floor) : nlohmann::json()},
                                      {"selection", p ? p->selection : ""},
                                      {"noise_sigma", p ? num(p->noise_sigma) : nlohmann::json()},
                                      {"weights", p ? p->weights : ""}};
                out.push_back(rec);
            }
        }
    }
    return out;
}

std::vector<std::vector<std::string>> ParseCsv(const std::string& text) {
    std::vector<std::vector<std::string>> records;
    std::vector<std::string> fields;
    std::string field;
    bool quoted = false, any = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (quoted) {
            if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
                field += '"';
                ++i;
            } else if (c == '"') {
                quoted = false;
            } else {
                field += c;
            }
            continue;
        }
        if (c == '"') {
            quoted = true;
            any = true;
        } else if (c == ',') {
            fields.push_back(field);
            field.clear();
        } else if (c == '\n') {
            fields.push_back(field);
            records.push_back(fields);
            fields.clear();
            field.clear();
            any = false;
        } else if (c != '\r') {
            field += c;
            any = true;
        }
    }
    if (any || !fields.empty()) {
        fields.push_back(field);
        records.push_back(fields);
    }
    return records;
}

}  // namespace regbench
