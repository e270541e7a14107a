#include "reports/curves.hpp"

#include <fmt/format.h>

#include <cmath>

#include "reports/row_access.hpp"

namespace regbench {

std::vector<SuccessCurve> DefaultSuccessCurves() { return {{"rre", 15.0}, {"rte", 0.3}}; }

double SuccessRateBelow(const std::vector<double>& errors, double threshold) {
    if (errors.empty()) return std::nan("");
    std::size_t below = 0;
    for (double e : errors) below += e < threshold ? 1 : 0;  // NaN compares false: a miss
    return static_cast<double>(below) / static_cast<double>(errors.size());
}

double SuccessAuc(const std::vector<double>& errors, double max) {
    if (errors.empty()) return std::nan("");
    double area = 0.0;
    for (double e : errors) {
        if (e < max) area += 1.0 - e / max;
    }
    return area / static_cast<double>(errors.size());
}

Table SuccessCurveTable(const std::vector<ResultRow>& rows, const SuccessCurve& curve,
                        int steps) {
    const MetricField& metric = FindMetric(curve.metric);
    const bool degrees = curve.metric == "rre" || curve.metric == "mae_r";
    const std::string unit = degrees ? "°" : "";
    Table t{"success_curve:" + curve.metric,
            fmt::format("Success rate against {} threshold", curve.metric),
            fmt::format("fraction of all pairs with {0} < x, at x = {1:g}{2} / {3} steps up to "
                        "{1:g}{2}; pairs with a null {0} count as misses; AUC: the area under the "
                        "curve on [0, {1:g}{2}] over {1:g}{2}, the mean of max(0, 1 - {0} / "
                        "{1:g}) over pairs (exact, no grid)",
                        curve.metric, curve.max, unit, steps)};
    t.columns.push_back({"pairs", "pairs", CellSource::kMeasured, Better::kNone, 0});
    std::vector<double> thresholds;
    for (int k = 1; k <= steps; ++k) {
        thresholds.push_back(curve.max * k / steps);
        t.columns.push_back({fmt::format("below:{:g}", thresholds.back()),
                             fmt::format("< {:g}{}", thresholds.back(), unit),
                             CellSource::kMeasured, Better::kHigher, kFractionDecimals,
                             CiStyle::kHidden});
    }
    t.columns.push_back({"auc", fmt::format("AUC@{:g}{}", curve.max, unit), CellSource::kMeasured,
                         Better::kHigher, kFractionDecimals, CiStyle::kHidden});
    for (const auto& method : MethodOrder(rows)) {
        std::vector<double> errors;
        for (const ResultRow* r : RowsOf(rows, method)) {
            errors.push_back(metric.Of(r->metrics).value_or(std::nan("")));
        }
        const std::size_t n = errors.size();
        RowCells cells = {{"pairs", MeasuredCell(static_cast<double>(n), n)}};
        for (double x : thresholds) {
            cells.emplace_back(fmt::format("below:{:g}", x),
                               MeasuredCell(SuccessRateBelow(errors, x), n));
        }
        cells.emplace_back("auc", MeasuredCell(SuccessAuc(errors, curve.max), n));
        t.AddRow(method, cells);
    }
    return t;
}

}  // namespace regbench
