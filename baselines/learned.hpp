#pragma once
// Learned methods (DeepGMR, OGMM) as regbench methods: batch-1 CPU inference of a checkpoint,
// optionally refined by Open3D point-to-point ICP as the OGMM authors' evaluation does.
#include <string>
#include <vector>

#include "core/registration.hpp"

namespace regbench {

/// The methods of every network family (networks/family.hpp), in the registry's order (today
/// `ogmm`, `ogmm-noicp`, `deepgmr`, `deepgmr-noicp`). Any checkpoint of the method's family
/// (its config.arch) runs under it, e.g. `deepgmr` with checkpoint = a deepgmr-orig run.
/// Creating the method opens checkpoint.json: a missing folder, an unreadable checkpoint, a
/// config its family refuses or one of another family is refused (std::invalid_argument
/// naming the folder).
std::vector<MethodInfo> LearnedMethodInfos();

/// Directory of the shipped checkpoint `name` (a family's shipped_model): $REGBENCH_MODELS/<name> when that
/// variable is set, else <source dir baked in at build time>/data/models/<name>.
std::string ShippedCheckpointDir(const std::string& name);

/// The shipped checkpoint folder learned method `method` runs when its checkpoint parameter is
/// "" (ShippedCheckpointDir of its family's shipped model); "" when `method` is not a learned
/// method.
std::string DefaultCheckpointDir(const std::string& method);

/// Which weights a learned method ran, as result rows and table captions name them.
struct CheckpointInfo {
    std::string dir;
    std::string label;   ///< "model M, step S" / "model M, imported (preset P)"
    std::string sha256;  ///< of the weights file (the folder's checkpoint.json "weights")
    /// "shipped" (under the shipped models folder), "authors" (imported from the authors'
    /// file) or "trained" (a user's `regbench train` folder elsewhere)
    std::string source;
};
/// Describes checkpoint folder `dir`; throws std::runtime_error naming it when its
/// checkpoint.json or weights file cannot be read.
CheckpointInfo DescribeCheckpoint(const std::string& dir);

/// The per-pair normalisation of the learned methods (parameter `normalize`, default true;
/// docs/learned-methods.md, "Scale and normalisation"). The networks were trained on the paper's
/// protocol: unit-sphere objects moved by at most 0.5 per axis, i.e. clouds inside the ball of
/// radius kTrainingFrameRadius about the origin. A pair outside it (millimetres, a room scan in
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
/// The normalisation of (source, target): unchanged when every point of both lies within
/// kTrainingFrameRadius of the origin (or the source is empty), else the source's centroid and
/// radius (1 for a source of coincident points).
PairNormalization NormalizationOf(const PointCloud& source, const PointCloud& target);
/// (x - centre) / scale for every point; `cloud` itself when !n.applied.
PointCloud NormalizeCloud(const PointCloud& cloud, const PairNormalization& n);
/// The data-frame transform of an estimate `T_normalized` = (R', t') made on normalised clouds:
/// from y' = R' x' + t', x' = (x - c) / s, y' = (y - c) / s follows y = R x + t with R = R',
/// t = s t' + c - R' c. `T_normalized` itself when !n.applied.
Transform DenormalizeTransform(const Transform& T_normalized, const PairNormalization& n);

/// ICP refinement settings of the OGMM evaluation: Open3D point-to-point ICP started from the
/// network's estimate.
struct IcpRefineOptions {
    double max_correspondence_distance = 0.07;  ///< 2 * overlap_radius (0.035, ModelNet)
    int max_iterations = 30;                    ///< Open3D default
    double relative_fitness = 1e-6;             ///< Open3D default
    double relative_rmse = 1e-6;                ///< Open3D default
};

/// Open3D ICP from `initial` (the source moved by `initial`, ICP from the identity, composed).
/// `details`, when given, receives ICP's AlignResult (iterations, fitness, inlier_rmse).
Transform IcpRefine(const PointCloud& source, const PointCloud& target, const Transform& initial,
                    const IcpRefineOptions& options = {}, AlignResult* details = nullptr);

}  // namespace regbench
