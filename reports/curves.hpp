#pragma once
// Success rate against threshold (issue 54 item 3): for one error metric, the fraction of all
// pairs whose error is below each threshold up to a maximum, and the area under that curve.
#include <string>
#include <vector>

#include "reports/table.hpp"
#include "runners/result_row.hpp"

namespace regbench {

/// One curve: the metric (rre, rte, mae_r, ...; reports/row_access.hpp) and the largest
/// threshold, in the metric's unit (degrees or data units).
struct SuccessCurve {
    std::string metric;
    double max = 0.0;
};

/// rre up to 15 degrees and rte up to 0.3 data units (the 3DMatch-style bounds).
std::vector<SuccessCurve> DefaultSuccessCurves();

/// The fraction of `errors` strictly below `threshold`; a NaN error (a pair whose metrics are
/// null) counts as a miss. NaN when there are no errors.
double SuccessRateBelow(const std::vector<double>& errors, double threshold);

/// The normalised area under the success-rate curve on [0, max]: (1 / max) times the integral
/// of SuccessRateBelow(errors, x) dx from 0 to max. Each pair contributes (max - e) / max when
/// e < max and 0 otherwise (NaN: 0), so the area is the mean of max(0, 1 - e / max): exact,
/// with no grid. 1: every error 0; 0: none below max. NaN when there are no errors.
double SuccessAuc(const std::vector<double>& errors, double max);

/// A table "success_curve:<metric>": a row per method, the success rate at `steps` thresholds
/// evenly spaced up to curve.max (max / steps, 2 max / steps, ..., max) over all its pairs,
/// and the AUC (SuccessAuc).
Table SuccessCurveTable(const std::vector<ResultRow>& rows, const SuccessCurve& curve,
                        int steps = 5);

}  // namespace regbench
