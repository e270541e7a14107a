#pragma once
// The conventions a summary table follows, named, switchable and printed in its caption
// (issue 54 item 3; docs/metrics.md, "Conventions"): which pairs RRE/RTE average over, whether
// rates average over pairs or over scenes, and the success rule (the flags' pair or a named
// preset of the registration literature).
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/metrics.hpp"
#include "reports/statistics.hpp"

namespace regbench {

/// Which pairs the means of rre and rte average over.
enum class ErrorPairs {
    kAll,         ///< every pair with finite metrics (the default; the paper's tables)
    kSuccessful,  ///< only pairs the success rule accepts (GeoTransformer's eval.py on KITTI)
};
/// "all", "successful".
const char* ToString(ErrorPairs e);
/// Inverse of ToString; throws std::invalid_argument naming the value and the choices.
ErrorPairs ParseErrorPairs(const std::string& name);

/// What a rate (recall, success, 3DMatch recall) is averaged over.
enum class RatePer {
    kPair,      ///< the fraction of pairs (the default), with its Wilson interval
    kScene,     ///< the mean over scenes (the pair's `shape`) of each scene's fraction
    kCategory,  ///< the same over the pair's `category`
};
/// "pair", "scene", "category".
const char* ToString(RatePer r);
/// Inverse of ToString; throws std::invalid_argument naming the value and the choices.
RatePer ParseRatePer(const std::string& name);

/// A success rule: a pair succeeds when every finite bound holds (strictly below); a NaN metric
/// fails. Bounds left infinite are not tested.
struct SuccessRule {
    std::string name;    ///< "rre-rte" (the flags) or a preset's name
    std::string origin;  ///< where the rule comes from, for the caption
    double mae_r_deg = std::numeric_limits<double>::infinity();
    double mae_t = std::numeric_limits<double>::infinity();
    double rre_deg = std::numeric_limits<double>::infinity();
    double rte = std::numeric_limits<double>::infinity();
    double overlap_rmse = std::numeric_limits<double>::infinity();
    bool Passes(const PairMetrics& m) const;
    /// The bounds as "rre<5,rte<0.1" (in mae_r, mae_t, rre, rte, rmse order).
    std::string Bounds() const;
    /// The column header: "success(rre<5,rte<0.1)" for "rre-rte" (as before rules had names),
    /// "success kitti(rre<5,rte<2)" for a preset.
    std::string Header() const;
};

/// The named presets, in this order: "paper-recall" (mae_r < 1 deg and mae_t < 0.1: the OGMM
/// code's recall), "3dmatch-rmse" (overlap_rmse < 0.2: the 3DMatch registration recall over
/// ground-truth correspondences, Predator / GeoTransformer), "kitti" (rre < 5 deg and rte < 2),
/// "3dmatch-rre-rte" (rre < 15 deg and rte < 0.3). Thresholds in the data's units.
const std::vector<SuccessRule>& SuccessRulePresets();

/// "rre-rte" and the presets' names.
std::vector<std::string> SuccessRuleNames();

/// The rule named `name`: "rre-rte" is rre < rre_deg and rte < rte (`report --success-rre`,
/// `--success-rte`); otherwise a preset, its distance bounds (mae_t, rte, overlap_rmse) times
/// `distance_scale` (the pair file's scale: presets are in unit-sphere units for objects and
/// in metres for scans). Throws std::invalid_argument listing the names.
SuccessRule FindSuccessRule(const std::string& name, double rre_deg, double rte,
                            double distance_scale = 1.0);

/// A rate over one table row's pairs. hits[k]: pair k passed; groups[k]: its scene (or
/// category) id, read only when `per` is not kPair. kPair: WilsonInterval(sum, n), exactly as
/// before rates could be averaged otherwise. kScene / kCategory: the mean over the distinct
/// groups of each group's fraction, with the 95% percentile-bootstrap CI of that mean over the
/// groups (BootstrapMean, `samples` resamples on `stream`); `groups_out` receives how many.
BootstrapCi Rate(const std::vector<bool>& hits, const std::vector<std::string>& groups,
                 RatePer per, int samples, std::uint64_t stream, std::size_t* groups_out);

struct ResultRow;

/// The caption line of the paper tables (reproduce's tables.md, `report --paper`): what their
/// means average over and which convention their metrics follow, then the thresholds `rows`
/// were measured with in the data's length unit (the CCD clip; the pair files' scale when it is
/// not 1) and a "Saturated:" sentence when every method's mean CCD is at its ceiling 2 x clip
/// (issue 54 item 1).
std::string PaperTableConventions(const std::vector<const ResultRow*>& rows);

}  // namespace regbench
