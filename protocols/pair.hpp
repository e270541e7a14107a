#pragma once
// One registration pair as frozen in a benchmark file (schema: docs/benchmark-format.md).
#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"

namespace regbench {

struct Pair {
    PointCloud source;
    PointCloud target;
    Transform T_gt = Transform::Identity();  ///< maps source into the target frame
    Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> source_overlap;  ///< 1 = overlaps (eta)
    Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> target_overlap;
    double source_overlap_ratio = 0.0;  ///< fraction of source points labelled overlapping
    double target_overlap_ratio = 0.0;
    std::string shape;     ///< mesh / scan name
    std::string category;  ///< its category
    /// Per-pair generation details (e.g. {"source_keep": 0.7, "target_keep": 0.7}); stored as
    /// the optional JSON string attribute "meta" (absent or empty object when none).
    nlohmann::json meta = nlohmann::json::object();
};

/// A frozen benchmark: pairs plus provenance (protocol, parameters, seed, dataset, version).
struct PairSet {
    nlohmann::json provenance = nlohmann::json::object();
    std::vector<Pair> pairs;
};

}  // namespace regbench
