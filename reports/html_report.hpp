#pragma once
// One self-contained HTML report: tables, inline SVG plots, no script, no network.
#include <functional>
#include <string>
#include <vector>

#include "protocols/pair.hpp"
#include "reports/curves.hpp"
#include "reports/table.hpp"
#include "runners/result_row.hpp"

namespace regbench {

/// The pair a result row was measured on, or nullptr when its pair file is not at hand.
using PairLookup = std::function<const Pair*(const ResultRow& row)>;

/// One result set (one pair file): its plots and tables.
struct HtmlSection {
    std::string title;  ///< e.g. "Tab. 1 same-category: partial, cgal test"
    std::string description;
    std::vector<ResultRow> rows;
    std::vector<Table> tables;
    PairLookup pair_lookup;  ///< for the gallery; empty: no gallery
    std::vector<SuccessCurve> curves;  ///< success-rate curves drawn beside the error CDF
};

struct HtmlReportOptions {
    std::string title = "regbench report";
    std::vector<std::string> intro;  ///< paragraphs under the title (command, machine, ...)
    std::vector<Table> tables;       ///< the paper's tables, shown first
    std::vector<HtmlSection> sections;
    int gallery_per_method = 2;  ///< worst pairs drawn per method
    int gallery_points = 400;    ///< points drawn per cloud (evenly subsampled)
    double cdf_max_deg = 45.0;   ///< x range of the error CDF
};

/// The whole page; every character of it is produced here (no external resource).
std::string RenderHtmlReport(const HtmlReportOptions& options);

/// A table as an HTML <table> (best cell per column bold, paper-only columns in grey).
std::string TableToHtml(const Table& t, TableForm form = TableForm::kCompact);

/// The legend above the paper's tables, saying what their compact HTML shows: the paper's
/// values in parentheses after ours where a column holds both ("measured (paper)", its header
/// ending in "(paper)"), grey columns only where a table has a paper column standing alone,
/// and that bold marks the best measured cell of a column.
std::string PaperTablesLegend(const std::vector<Table>& tables);

/// Axis ticks at round numbers: linear, multiples of a step of 1, 2 or 5 times a power of ten
/// (about four intervals) within [lo, hi]; log, the powers of ten within it (with their 2x and
/// 5x when fewer than two).
std::vector<double> NiceTicks(double lo, double hi, bool log);

/// Error CDF: fraction of pairs with mae_r below x, one curve per method (inline <svg>).
std::string ErrorCdfSvg(const std::vector<ResultRow>& rows, double max_deg);

/// Success rate against threshold: the fraction of all pairs with curve.metric below x for x
/// in [0, curve.max] (a non-finite metric never counts), one step curve per method.
std::string SuccessCurveSvg(const std::vector<ResultRow>& rows, const SuccessCurve& curve,
                            const std::string& axis);

/// mae_r against the pair's measured overlap (min of both ratios), one colour per method.
std::string ErrorVsOverlapSvg(const std::vector<ResultRow>& rows);

/// Mean mae_r against median seconds per pair (log axis), one labelled point per method.
std::string TimeVsAccuracySvg(const std::vector<ResultRow>& rows);

/// One pair drawn as an x-y projection: target (grey), source (red), aligned source (green).
std::string PairProjectionSvg(const Pair& pair, const Transform& estimate, int max_points);

}  // namespace regbench
