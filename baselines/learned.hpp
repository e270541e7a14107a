#pragma once
// Learned methods (DeepGMR, OGMM) as regbench methods: batch-1 CPU inference of a checkpoint,
// optionally refined by Open3D point-to-point ICP as the OGMM authors' evaluation does.
#include <string>
#include <vector>

#include "core/pair_normalization.hpp"
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
