#pragma once
// What `regbench inspect` prints about a pair file.
#include <array>
#include <nlohmann/json.hpp>
#include <string>

#include "protocols/pair.hpp"

namespace regbench {

/// Overlap histogram bins: [0, 0.1), [0.1, 0.2), ..., [0.9, 1.0].
constexpr int kOverlapBins = 10;

struct PairSetSummary {
    std::size_t pairs = 0;
    long min_source_points = 0, max_source_points = 0;
    long min_target_points = 0, max_target_points = 0;
    double min_rotation_deg = 0.0, max_rotation_deg = 0.0;  ///< angle of R_gt
    double min_translation = 0.0, max_translation = 0.0;    ///< |t_gt|
    double mean_source_overlap = 0.0, mean_target_overlap = 0.0;
    std::array<int, kOverlapBins> source_overlap_histogram{};  ///< pairs per overlap-ratio bin
    double gt_ccd_mean = 0.0;  ///< mean CCD of T_gt itself: the floor any method can reach
};

/// Summarises every pair (the CCD floor costs two kd-tree passes per pair).
PairSetSummary SummarizePairSet(const PairSet& set);
nlohmann::json ToJson(const PairSetSummary& s);
/// Human-readable multi-line text.
std::string FormatSummary(const PairSetSummary& s);

}  // namespace regbench
