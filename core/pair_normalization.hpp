#pragma once
// One similarity that maps a pair outside the networks' training frame into it, and back.

#include <Eigen/Core>

#include "core/point_cloud.hpp"
#include "core/transform.hpp"

namespace regbench {

/// The per-pair normalisation of the learned methods (their parameter `normalize`, default
/// true, in baselines/learned.cpp) and of their training samples (experiments/training_bundle.cpp,
/// so a network sees in training what it sees at inference; docs/learned-methods.md, "Scale and
/// normalisation"). The networks are trained on the paper's protocol: unit-sphere objects moved
/// by at most 0.5 per axis, i.e. clouds inside the ball of radius kTrainingFrameRadius about the
/// origin. A pair outside it (millimetres, a room scan in
/// its camera frame) is mapped into the unit sphere by one similarity for both clouds,
/// x -> (x - c) / s with c the source's centroid and s its radius, so the source is a centred
/// unit-sphere cloud as the paper's objects are and the target keeps its motion relative to it.
/// The method runs there (network and ICP refinement, whose radius is in training units), and
/// its estimate is mapped back (DenormalizeTransform), so the reported R is the network's and t
/// is in the data's units. A pair inside that ball is passed unchanged, so the paper's object
/// protocols give bit-identical results with and without it.
struct PairNormalization {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< c: the source's centroid
    double scale = 1.0;    ///< s: the largest distance of a source point from c
    bool applied = false;  ///< false: the pair was inside the training frame, left unchanged
};
/// Radius of the ball about the origin that the training pairs' clouds lie in (1 + 0.5 * sqrt 3
/// + the noise clip, rounded up).
inline constexpr double kTrainingFrameRadius = 2.0;
/// The normalisation of (source, target) whose length unit is `data_unit` data units (the pair
/// file's scale: 150 for `generate --scale 150`, 1 for the paper's unit-sphere pairs): when every
/// point of both lies within kTrainingFrameRadius * data_unit of the origin (or the source is
/// empty), the pair is divided by data_unit (unchanged when it is 1), so a scaled copy of a pair
/// runs as the unit pair does; else the source's centroid and radius (1 for a source of
/// coincident points).
PairNormalization NormalizationOf(const PointCloud& source, const PointCloud& target,
                                  double data_unit = 1.0);
/// (x - centre) / scale for every point; `cloud` itself when !n.applied.
PointCloud NormalizeCloud(const PointCloud& cloud, const PairNormalization& n);
/// The data-frame transform of an estimate `T_normalized` = (R', t') made on normalised clouds:
/// from y' = R' x' + t', x' = (x - c) / s, y' = (y - c) / s follows y = R x + t with R = R',
/// t = s t' + c - R' c. `T_normalized` itself when !n.applied.
Transform DenormalizeTransform(const Transform& T_normalized, const PairNormalization& n);
/// The ground truth of the normalised pair: from y = R x + t and x = s x' + c, y = s y' + c
/// follows y' = R x' + t' with t' = (t + R c - c) / s. `T` itself when !n.applied.
Transform NormalizeGroundTruth(const Transform& T, const PairNormalization& n);

}  // namespace regbench
