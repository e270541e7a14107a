#pragma once
// Report tables as data: rows of cells with the provenance of what was measured, written to
// Markdown, LaTeX (booktabs), CSV and JSON by reports/table_writers.cpp.
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace regbench {

/// Where a cell's number came from.
enum class CellSource {
    kLabel,     ///< a row label or free text, not a number
    kMeasured,  ///< computed from regbench result rows
    kPaper,     ///< transcribed from the paper (data/paper/ogmm_wacv2023_tables.json)
};

struct Cell {
    double value = std::nan("");  ///< NaN: empty cell ("-") unless `text` is set
    double ci_lo = std::nan("");  ///< 95% CI of the value (NaN: none), shown per Column::ci
    double ci_hi = std::nan("");
    std::string text;  ///< overrides the number (e.g. "not trained")
    CellSource source = CellSource::kMeasured;
    std::size_t pairs = 0;  ///< rows the number was computed from (measured cells)
    bool HasValue() const { return std::isfinite(value); }
    double HalfWidth() const { return 0.5 * (ci_hi - ci_lo); }  ///< NaN without a CI
};

/// A measured number computed from `pairs` result rows.
inline Cell MeasuredCell(double value, std::size_t pairs) {
    Cell c;
    c.value = value;
    c.pairs = pairs;
    return c;
}

/// How a column shows its cells' CIs in Markdown, LaTeX and HTML (CSV and JSON carry them all).
enum class CiStyle {
    kPlusMinus,      ///< "mean ± half-width"
    kInterval,       ///< "[lo, hi]" instead of the value (a left-aligned column)
    kHidden,         ///< the value only
    kValueInterval,  ///< "value [lo, hi]": an interval not centred on the value (a rate's Wilson)
};

/// Which Markdown / HTML table a writer shows. Compact (the default): the columns marked
/// `compact`, each number rounded to its CI (the half-width to two significant digits, the
/// value to the same place; a rate to 2 decimals), Markdown's "mean±half-width" without
/// spaces, and a paper column merged into the measured one before it as "measured (paper)".
/// Full: every shown column at its decimals.
enum class TableForm { kCompact, kFull };

/// Which way is better, for bolding the best cell of a column.
enum class Better { kNone, kLower, kHigher };

struct Column {
    std::string key;  ///< machine name, e.g. "same_category.mae_r" or "paper:same_category.mae_r"
    std::string header;  ///< shown name, e.g. "MAE(R) same"
    CellSource source = CellSource::kMeasured;
    Better better = Better::kLower;
    int decimals = 4;  ///< one per quantity: reports/row_access.hpp
    CiStyle ci = CiStyle::kPlusMinus;
    bool shown = true;    ///< false: a data column, in CSV and JSON only (e.g. a method's params)
    bool compact = true;  ///< false: shown in the full table only (TableForm::kFull)
};

/// Where a table's measured numbers came from: one entry per result set used.
struct Provenance {
    std::string group;       ///< the column group these rows fill ("same_category", "" for all)
    std::string pairs_file;  ///< pair file name
    std::string pairs_hash;  ///< its content hash when the rows record one
    std::string dataset, split, protocol, pairing;
    nlohmann::json seed;   ///< number or null
    int points = 0;        ///< points per cloud before cropping (0: unknown)
    double keep = 0.0;     ///< crop fraction (0: unknown / none)
    std::string version;   ///< regbench version / git sha that wrote the pair file
    std::string fallback;  ///< non-empty when the paper's dataset was replaced, and by what
    double gt_ccd_floor = std::nan("");  ///< mean CCD of the ground-truth alignment
    /// Which items the pairs use: "one-per-item" (`generate --pairs all`), "cycle" (pair k
    /// uses item k mod items), "" when the pair file does not say (older files).
    std::string selection;
    double noise_sigma = std::nan("");  ///< jitter sigma applied (0: noise-free; NaN: unknown)
    /// The weights each learned method ran on these pairs ("ogmm = model ogmm-small, step 523
    /// (shipped, sha256 ...); ..."); "" when no learned method ran.
    std::string weights;
};

struct Table;

/// One row of a Table: its label and a cell per column, keyed by the column's key, so a cell
/// cannot land under another column's header. Cells are set through Table::AddRow, which
/// refuses a key the table has no column for.
class TableRow {
public:
    TableRow() = default;
    explicit TableRow(std::string label_) : label(std::move(label_)) {}

    std::string label;  ///< method (or parameter value for the supplementary tables)

    /// The cell under the column with `key`; an empty cell ("-") when the row has none there.
    const Cell& Get(const std::string& key) const;

private:
    friend struct Table;
    std::map<std::string, Cell> cells_;
};

/// A row's cells as (column key, cell), in any order.
using RowCells = std::vector<std::pair<std::string, Cell>>;

struct Table {
    Table() = default;
    Table(std::string id_, std::string title_, std::string caption_)
        : id(std::move(id_)), title(std::move(title_)), caption(std::move(caption_)) {}

    std::string id;       ///< e.g. "table1_modelnet_partial"
    std::string title;    ///< e.g. "Tab. 1: partial-to-partial"; "" for no heading
    std::string caption;  ///< names the data each side came from and the pairing
    std::string row_header = "method";
    std::vector<Column> columns;
    /// Column groups, e.g. "same_category": a column whose key (less "paper:") starts with
    /// "<group>." is in it, its header names it. A compact Markdown table too wide for 120
    /// columns is shown one group at a time.
    std::vector<std::string> column_groups;
    std::vector<TableRow> rows;
    std::vector<Provenance> provenance;
    std::vector<std::string> notes;  ///< extra lines printed under the table

    /// Appends a row with its cells keyed by column key (columns without a cell show "-").
    /// Throws std::logic_error naming the table, row and key for a key no column has, a key
    /// given twice, or a table whose columns repeat a key.
    TableRow& AddRow(std::string label, const RowCells& cells);

    /// The index of the column with `key`; throws std::logic_error when there is none.
    std::size_t ColumnIndex(const std::string& key) const;
};

/// A cell as the text writers show it: its text, else the number with `col.decimals` (and its
/// CI as `col.ci` says, joined by `pm`), "-" when empty. Compact: rounded to its CI instead.
std::string CellText(const Cell& cell, const Column& col, const char* pm,
                     TableForm form = TableForm::kFull);

/// A table as the Markdown and HTML writers show it: one entry per shown column of `form`.
struct ShownTable {
    struct ShownColumn {
        std::string header;
        bool left = false;   ///< left-aligned (an interval column)
        bool paper = false;  ///< the paper's numbers
        std::string group;   ///< its Table::column_groups entry, "" for none
        /// Compact form: a measured column with the paper's column merged into it, each cell
        /// "measured (paper)" and the header ending in " (paper)".
        bool with_paper = false;
    };
    std::vector<ShownColumn> columns;
    std::vector<std::string> labels;              ///< one per row
    std::vector<std::vector<std::string>> cells;  ///< [row][shown column], unescaped
    std::vector<std::vector<bool>> best;          ///< [row][shown column]: bold it
};
ShownTable ShowTable(const Table& t, TableForm form, const char* pm);

/// The distinct data-source notes of a table's provenance (Provenance::fallback, e.g. "embedded
/// CGAL mesh corpus instead of ModelNet40"), which the writers show as a line of their own.
std::vector<std::string> DataSources(const Table& t);

/// Markdown: title, caption, pipe table (measured ± half-width), notes.
std::string TableToMarkdown(const Table& t, TableForm form = TableForm::kCompact);

/// LaTeX table environment with booktabs rules; the best measured cell of each column with a
/// `better` direction is bold, CIs as "mean $\pm$ half-width"; caption escaped.
std::string TableToLatex(const Table& t);

/// CSV, one line per (table, row, column) with the provenance fields, header included.
std::string TablesToCsv(const std::vector<Table>& tables);

/// Each table's Markdown, one blank line between tables.
std::string TablesToMarkdown(const std::vector<Table>& tables,
                             TableForm form = TableForm::kCompact);

/// JSON array with one object per (table, row, column) and structured provenance.
nlohmann::json TablesToJson(const std::vector<Table>& tables);

/// Parses TablesToCsv output back into flat records (for round-trip checks and tools).
std::vector<std::vector<std::string>> ParseCsv(const std::string& text);

/// Index of the best cell of column `c` among rows (by value), or -1.
int BestRow(const Table& t, std::size_t c);

}  // namespace regbench
