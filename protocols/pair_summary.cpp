#include "protocols/pair_summary.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>

#include "core/metrics.hpp"
#include "core/transform.hpp"

namespace regbench {

PairSetSummary SummarizePairSet(const PairSet& set) {
    PairSetSummary s;
    s.pairs = set.pairs.size();
    if (set.pairs.empty()) return s;
    s.min_source_points = s.min_target_points = std::numeric_limits<long>::max();
    s.min_rotation_deg = s.min_translation = std::numeric_limits<double>::infinity();
    for (const Pair& p : set.pairs) {
        s.min_source_points = std::min(s.min_source_points, static_cast<long>(p.source.rows()));
        s.max_source_points = std::max(s.max_source_points, static_cast<long>(p.source.rows()));
        s.min_target_points = std::min(s.min_target_points, static_cast<long>(p.target.rows()));
        s.max_target_points = std::max(s.max_target_points, static_cast<long>(p.target.rows()));
        const double angle =
            RotationAngleDeg(Eigen::Matrix3d::Identity(), p.T_gt.topLeftCorner<3, 3>());
        const double shift = p.T_gt.topRightCorner<3, 1>().norm();
        s.min_rotation_deg = std::min(s.min_rotation_deg, angle);
        s.max_rotation_deg = std::max(s.max_rotation_deg, angle);
        s.min_translation = std::min(s.min_translation, shift);
        s.max_translation = std::max(s.max_translation, shift);
        s.mean_source_overlap += p.source_overlap_ratio;
        s.mean_target_overlap += p.target_overlap_ratio;
        const int bin = std::clamp(static_cast<int>(p.source_overlap_ratio * kOverlapBins), 0,
                                   kOverlapBins - 1);
        ++s.source_overlap_histogram[static_cast<std::size_t>(bin)];
        s.gt_ccd_mean += ChamferDistances(Apply(p.T_gt, p.source), p.target).ccd;
    }
    const auto n = static_cast<double>(s.pairs);
    s.mean_source_overlap /= n;
    s.mean_target_overlap /= n;
    s.gt_ccd_mean /= n;
    return s;
}

nlohmann::json ToJson(const PairSetSummary& s) {
    return {{"pairs", s.pairs},
            {"source_points", {s.min_source_points, s.max_source_points}},
            {"target_points", {s.min_target_points, s.max_target_points}},
            {"rotation_deg", {s.min_rotation_deg, s.max_rotation_deg}},
            {"translation", {s.min_translation, s.max_translation}},
            {"mean_source_overlap", s.mean_source_overlap},
            {"mean_target_overlap", s.mean_target_overlap},
            {"source_overlap_histogram", s.source_overlap_histogram},
            {"gt_ccd_mean", s.gt_ccd_mean}};
}

std::string FormatSummary(const PairSetSummary& s) {
    char buf[256];
    std::string out;
    std::snprintf(buf, sizeof(buf), "pairs: %zu\n", s.pairs);
    out += buf;
    std::snprintf(buf, sizeof(buf), "source points: %ld .. %ld\ntarget points: %ld .. %ld\n",
                  s.min_source_points, s.max_source_points, s.min_target_points,
                  s.max_target_points);
    out += buf;
    std::snprintf(buf, sizeof(buf),
                  "rotation angle of T_gt [deg]: %.3f .. %.3f\n|t_gt|: %.4f .. %.4f\n",
                  s.min_rotation_deg, s.max_rotation_deg, s.min_translation, s.max_translation);
    out += buf;
    std::snprintf(buf, sizeof(buf), "mean overlap ratio: source %.4f, target %.4f\n",
                  s.mean_source_overlap, s.mean_target_overlap);
    out += buf;
    out += "source overlap histogram (pairs per ratio bin):\n";
    for (int b = 0; b < kOverlapBins; ++b) {
        std::snprintf(buf, sizeof(buf), "  [%.1f, %.1f%c %d\n", b / 10.0, (b + 1) / 10.0,
                      b + 1 == kOverlapBins ? ']' : ')',
                      s.source_overlap_histogram[static_cast<std::size_t>(b)]);
        out += buf;
    }
    std::snprintf(buf, sizeof(buf), "ground-truth CCD floor (mean CCD of T_gt): %.5f\n",
                  s.gt_ccd_mean);
    out += buf;
    return out;
}

}  // namespace regbench
