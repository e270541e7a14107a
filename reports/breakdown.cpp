#include "reports/breakdown.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <optional>
#include <set>

#include "core/enum_names.hpp"
#include "core/math_constants.hpp"
#include "reports/row_access.hpp"
#include "reports/statistics.hpp"

namespace regbench {
Table DistributionTable(const std::vector<ResultRow>& rows, const BreakdownOptions& o) {
    Table t{
        "distribution", "Per-method distribution of every metric",
        fmt::format("mean ± half-width of the 95% percentile-bootstrap CI ({} resamples, seed {}), "
                    "median and sample std over pairs with a finite value",
                    o.bootstrap_samples, o.seed)};
    t.columns.push_back({"pairs", "pairs", CellSource::kMeasured, Better::kNone, 0});
    for (const auto& m : o.metrics) {
        const int d = FindMetric(m).decimals;
        t.columns.push_back({m + ".mean", m + " mean", CellSource::kMeasured, Better::kLower, d});
        // Compact: the mean with its CI; median and std in the full table.
        t.columns.push_back(
            {m + ".median", m + " median", CellSource::kMeasured, Better::kLower, d});
        t.columns.back().compact = false;
        t.columns.push_back({m + ".std", m + " std", CellSource::kMeasured, Better::kNone, d});
        t.columns.back().compact = false;
    }
    for (const auto& method : MethodOrder(rows)) {
        const auto group = RowsOf(rows, method);
        RowCells cells = {{"pairs", MeasuredCell(static_cast<double>(group.size()), group.size())}};
        for (const auto& m : o.metrics) {
            const MetricField& metric = FindMetric(m);
            std::vector<double> v;
            for (const ResultRow* r : group) {
                if (const auto x = metric.Of(r->metrics)) v.push_back(*x);
            }
            // Streams named by the metric alone: every method draws the same resamples.
            const BootstrapCi ci = BootstrapMean(v, o.bootstrap_samples, o.seed, StreamId(m));
            Cell mean = MeasuredCell(ci.mean, v.size());
            if (v.size() >= 2) {
                mean.ci_lo = ci.lo;
                mean.ci_hi = ci.hi;
            }
            cells.emplace_back(m + ".mean", mean);
            cells.emplace_back(m + ".median", MeasuredCell(SampleMedian(v), v.size()));
            cells.emplace_back(m + ".std", MeasuredCell(SampleStd(v), v.size()));
        }
        t.AddRow(method, cells);
    }
    return t;
}

Table StatusTable(const std::vector<ResultRow>& rows) {
    Table t{
        "status", "Calls per status",
        "ok / failed (the method reported failure) / timeout / crashed (isolated runs) / other; "
        "null metrics: rows whose metrics are missing or not finite, counted as failures"};
    const std::vector<std::string> statuses = {"ok", "failed", "timeout", "crashed", "other"};
    for (const auto& s : statuses) {
        t.columns.push_back({s, s, CellSource::kMeasured, Better::kNone, 0});
    }
    t.columns.push_back({"null_metrics", "null metrics", CellSource::kMeasured, Better::kNone, 0});
    for (const auto& method : MethodOrder(rows)) {
        const auto group = RowsOf(rows, method);
        std::map<std::string, std::size_t> count;
        std::size_t null_metrics = 0;
        for (const ResultRow* r : group) {
            std::string s = ToString(r->status);
            if (std::find(statuses.begin(), statuses.end(), s) == statuses.end()) s = "other";
            ++count[s];
            if (!std::isfinite(r->metrics.mae_r) || !std::isfinite(r->metrics.mae_t)) {
                ++null_metrics;
            }
        }
        RowCells cells;
        for (const auto& s : statuses) {
            cells.emplace_back(s, MeasuredCell(static_cast<double>(count[s]), group.size()));
        }
        cells.emplace_back("null_metrics",
                           MeasuredCell(static_cast<double>(null_metrics), group.size()));
        t.AddRow(method, cells);
    }
    return t;
}

Table RecallTable(const std::vector<ResultRow>& rows, const BreakdownOptions& o) {
    Table t{
        "recall", "Recall at several thresholds",
        "recall@(r, t): fraction of pairs with mae_r < r degrees and mae_t < t; pairs with null "
        "metrics count as misses"};
    t.columns.push_back({"pairs", "pairs", CellSource::kMeasured, Better::kNone, 0});
    for (const auto& [r, tt] : o.recall) {
        t.columns.push_back({fmt::format("recall@({:g},{:g})", r, tt),
                             fmt::format("@({:g}°, {:g})", r, tt), CellSource::kMeasured,
                             Better::kHigher, kFractionDecimals, CiStyle::kValueInterval});
    }
    for (const auto& method : MethodOrder(rows)) {
        const auto group = RowsOf(rows, method);
        RowCells cells = {{"pairs", MeasuredCell(static_cast<double>(group.size()), group.size())}};
        for (const auto& [r, tt] : o.recall) {
            std::size_t hit = 0;
            for (const ResultRow* x : group) {
                // A NaN (null) metric compares false: a miss.
                if (x->metrics.mae_r < r && x->metrics.mae_t < tt) ++hit;
            }
            const BootstrapCi w = WilsonInterval(hit, group.size());  // NaN when no pairs
            Cell cell = MeasuredCell(w.mean, group.size());
            cell.ci_lo = w.lo;
            cell.ci_hi = w.hi;
            cells.emplace_back(fmt::format("recall@({:g},{:g})", r, tt), cell);
        }
        t.AddRow(method, cells);
    }
    return t;
}

namespace {

/// Adds one row per method to `t`, whose columns are already set: each cell averages
/// o.key_metric over that method's rows which `column_of` puts in the cell's column (nullopt:
/// in none; rows without the metric count in none either).
template <class ColumnOf>
void AddMeanRows(Table& t, const std::vector<ResultRow>& rows, const BreakdownOptions& o,
                 const ColumnOf& column_of) {
    const MetricField& metric = FindMetric(o.key_metric);
    for (const auto& method : MethodOrder(rows)) {
        std::vector<std::vector<double>> cells(t.columns.size());
        for (const ResultRow* r : RowsOf(rows, method)) {
            const std::optional<std::size_t> column = column_of(*r);
            if (!column) continue;
            if (const auto x = metric.Of(r->metrics)) cells[*column].push_back(*x);
        }
        RowCells row;
        for (std::size_t c = 0; c < cells.size(); ++c) {
            Cell cell = MeasuredCell(SampleMean(cells[c]), cells[c].size());
            if (cells[c].size() >= 2) {
                const BootstrapCi ci =
                    BootstrapMean(cells[c], o.bootstrap_samples, o.seed,
                                  StreamId(o.key_metric + "/" + t.columns[c].key));
                cell.ci_lo = ci.lo;
                cell.ci_hi = ci.hi;
            }
            // The pairs behind each mean, shown in the cell: bins and categories are uneven.
            if (!cells[c].empty()) {
                const std::string number = CellText(cell, t.columns[c], " ± ");
                cell.text = fmt::format("{} (n={})", number, cells[c].size());
            }
            row.emplace_back(t.columns[c].key, cell);
        }
        t.AddRow(method, row);
    }
}

}  // namespace

Table CategoryTable(const std::vector<ResultRow>& rows, const BreakdownOptions& o) {
    Table t{"category", "Mean " + o.key_metric + " per category",
            "shape categories of the pairs; each cell averages the pairs of that category (n: how "
            "many)"};
    std::set<std::string> categories;
    for (const auto& r : rows) categories.insert(r.category);
    for (const auto& c : categories) {
        t.columns.push_back(
            {c, c, CellSource::kMeasured, Better::kLower, FindMetric(o.key_metric).decimals});
    }
    AddMeanRows(t, rows, o, [&](const ResultRow& r) -> std::optional<std::size_t> {
        const auto it = categories.find(r.category);
        return static_cast<std::size_t>(std::distance(categories.begin(), it));
    });
    return t;
}

Table OverlapTable(const std::vector<ResultRow>& rows, const BreakdownOptions& o) {
    Table t{
        "overlap", "Mean " + o.key_metric + " by measured overlap",
        "bins of the pair's measured overlap, min(source ratio, target ratio), as the pair file "
        "labels it; each cell averages the pairs in the bin (n: how many; also the JSON/CSV "
        "`pairs` field)"};
    for (std::size_t b = 0; b + 1 < o.overlap_edges.size(); ++b) {
        const double lo = o.overlap_edges[b];
        const double hi = std::min(1.0, o.overlap_edges[b + 1]);
        t.columns.push_back({fmt::format("overlap[{:g},{:g})", lo, hi),
                             fmt::format("[{:.0f}%, {:.0f}%{}", 100 * lo, 100 * hi,
                                         b + 2 == o.overlap_edges.size() ? "]" : ")"),
                             CellSource::kMeasured, Better::kLower,
                             FindMetric(o.key_metric).decimals});
    }
    std::size_t missing = 0;
    AddMeanRows(t, rows, o, [&](const ResultRow& r) -> std::optional<std::size_t> {
        const auto ov = MeasuredOverlap(r);
        if (!ov) {
            ++missing;
            return std::nullopt;
        }
        for (std::size_t b = 0; b < t.columns.size(); ++b) {
            if (*ov >= o.overlap_edges[b] && *ov < o.overlap_edges[b + 1]) return b;
        }
        return std::nullopt;
    });
    if (missing > 0) {
        t.notes.push_back(fmt::format(
            "{} rows carry no overlap ratios (written before rows recorded them) and are left "
            "out.",
            missing));
    }
    return t;
}

namespace {
constexpr EnumName<Difficulty> kDifficultyNames[] = {{Difficulty::kRotation, "rotation"},
                                                     {Difficulty::kTranslation, "translation"},
                                                     {Difficulty::kOverlap, "overlap"}};
}  // namespace

const char* ToString(Difficulty d) { return EnumToString(kDifficultyNames, d); }

std::optional<double> DifficultyOf(const ResultRow& r, Difficulty axis) {
    if (axis == Difficulty::kOverlap) return MeasuredOverlap(r);
    if (!r.gt_transform) return std::nullopt;
    if (axis == Difficulty::kTranslation) return r.gt_transform->block<3, 1>(0, 3).norm();
    // The geodesic angle of the ground-truth rotation, as rre measures it against identity.
    const double c = 0.5 * (r.gt_transform->block<3, 3>(0, 0).trace() - 1.0);
    return std::acos(std::clamp(c, -1.0, 1.0)) / kDegToRad;
}

Table DifficultyTable(const std::vector<ResultRow>& rows, const BreakdownOptions& o,
                      Difficulty axis) {
    const std::vector<double>& edges = axis == Difficulty::kRotation      ? o.rotation_edges
                                       : axis == Difficulty::kTranslation ? o.translation_edges
                                                                          : o.difficulty_overlap_edges;
    const char* what = axis == Difficulty::kRotation
                           ? "the rotation angle of the pair's ground truth (geodesic, degrees)"
                       : axis == Difficulty::kTranslation
                           ? "the length of the ground truth's translation (data units)"
                           : "the pair's measured overlap, min(source ratio, target ratio)";
    Table t{std::string("difficulty:") + ToString(axis),
            "Mean " + o.key_metric + " by " + ToString(axis) + " difficulty",
            std::string("bins of ") + what +
                "; each cell averages the pairs in the bin (n: how many; also the JSON/CSV "
                "`pairs` field); bins are [lo, hi), the last one closed"};
    // Easy first: a small motion, or a large overlap.
    static const char* kLevels[] = {"easy", "medium", "hard"};
    const std::size_t bins = edges.size() - 1;
    for (std::size_t b = 0; b < bins; ++b) {
        const std::size_t level = axis == Difficulty::kOverlap ? bins - 1 - b : b;
        const std::string name = bins == 3 ? kLevels[level] : fmt::format("bin {}", b + 1);
        const bool last = b + 1 == bins;
        const std::string hi = edges[b + 1] >= 1e300 ? "inf" : fmt::format("{:g}", edges[b + 1]);
        t.columns.push_back(
            {fmt::format("{}[{:g},{})", ToString(axis), edges[b], hi),
             fmt::format("{} [{:g}, {}{}", name, edges[b], hi, last && hi != "inf" ? "]" : ")"),
             CellSource::kMeasured, Better::kLower, FindMetric(o.key_metric).decimals});
    }
    // Overlap bins run hard to easy: shown easy first like the others.
    if (axis == Difficulty::kOverlap) std::reverse(t.columns.begin(), t.columns.end());
    std::size_t missing = 0;
    AddMeanRows(t, rows, o, [&](const ResultRow& r) -> std::optional<std::size_t> {
        const auto v = DifficultyOf(r, axis);
        if (!v) {
            ++missing;
            return std::nullopt;
        }
        for (std::size_t b = 0; b < bins; ++b) {
            const bool last = b + 1 == bins;
            if (*v >= edges[b] && (*v < edges[b + 1] || (last && *v <= edges[b + 1]))) {
                return axis == Difficulty::kOverlap ? bins - 1 - b : b;
            }
        }
        return std::nullopt;
    });
    if (missing > 0) {
        t.notes.push_back(fmt::format(
            "{} rows carry no {} (written before rows recorded them) and are left out.", missing,
            axis == Difficulty::kOverlap ? "overlap ratios" : "ground truth"));
    }
    return t;
}

std::vector<Table> DifficultyTables(const std::vector<ResultRow>& rows, const BreakdownOptions& o) {
    return {DifficultyTable(rows, o, Difficulty::kRotation),
            DifficultyTable(rows, o, Difficulty::kTranslation),
            DifficultyTable(rows, o, Difficulty::kOverlap)};
}

}  // namespace regbench
