#pragma once
// Scale-aware defaults for methods whose length parameters assume unit-sphere objects with
// ~1k points (FGR voxel and feature radii, NDT resolution, ICP correspondence distance).
//
// Rule (docs/performance.md, "Scale-aware defaults"):
//  - extent: L = RMS distance of the target's points from their centroid. The presets were
//    tuned on unit-sphere-normalised objects, where L is 0.3-1.0 (reference 0.6).
//  - unit u = L / 0.6 when that ratio is outside [0.5, 2], else exactly 1: objects at the
//    presets' scale keep the presets bit for bit, others get every length scaled by u.
//  - density: clouds with more than 2048 points (twice the ~1k the presets assume) are
//    voxel-downsampled first by methods that support it (FGR), at the method's voxel size.
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/enum_names.hpp"
#include "core/point_cloud.hpp"

namespace regbench {

constexpr double kScaleRuleReferenceRadius = 0.6;      ///< L of a typical unit-sphere object
constexpr double kScaleRuleBand = 2.0;                 ///< u = 1 while L / reference in [1/2, 2]
constexpr Eigen::Index kScaleRulePresetPoints = 2048;  ///< above: downsample where supported
/// The doc of the `scale_rule_radius` parameter every method with a `scale_rule` binds.
inline constexpr const char* kScaleRuleRadiusDoc =
    "target RMS radius the presets were tuned at [unit-sphere units]; 0.6 = a typical "
    "unit-sphere object (docs/performance.md, section 4)";

/// The `scale_rule` option of FGR, NDT and ICP.
enum class ScaleRuleMode {
    kAuto,    ///< length parameters times the pair's unit (and FGR downsampling when dense)
    kPreset,  ///< the values as given (the paper's setting)
};
REGBENCH_CHOICES(ScaleRuleMode,
                 {{ScaleRuleMode::kAuto, "auto"}, {ScaleRuleMode::kPreset, "preset"}})

struct ScaleRule {
    double rms_radius = 0.0;  ///< L of the target
    double unit = 1.0;        ///< factor for every unit-sphere length parameter
    bool dense = false;       ///< max(source, target) points > kScaleRulePresetPoints
    nlohmann::json ToJson() const {
        return {{"rms_radius", rms_radius}, {"unit", unit}, {"dense", dense}};
    }
};

/// The rule above for one pair; O(N). `reference_radius` is the methods' `scale_rule_radius`, a
/// length like the presets it guards: `run` multiplies it by a scaled pair file's scale with
/// them, so a copy of a pair x150 gets the same unit (u) as the unit pair.
inline ScaleRule ResolveScaleRule(const PointCloud& source, const PointCloud& target,
                                  double reference_radius = kScaleRuleReferenceRadius) {
    ScaleRule r;
    const Eigen::RowVector3d c = target.colwise().mean();
    r.rms_radius = std::sqrt((target.rowwise() - c).rowwise().squaredNorm().mean());
    const double ratio = r.rms_radius / reference_radius;
    r.unit =
        (ratio > 0.0 && (ratio < 1.0 / kScaleRuleBand || ratio > kScaleRuleBand)) ? ratio : 1.0;
    r.dense = std::max(source.rows(), target.rows()) > kScaleRulePresetPoints;
    return r;
}

}  // namespace regbench
