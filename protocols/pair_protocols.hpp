#pragma once
// Pair protocols of the OGMM paper (docs/benchmark-format.md): partial, jitter, density,
// complete, complete-to-partial, overlap-sweep, indoor; independent or shared-sample pairing.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "protocols/pair.hpp"
#include "protocols/shape_source.hpp"

namespace regbench {

enum class Protocol {
    kPartial,            ///< Tab. 1: both clouds cropped to `keep`
    kJitter,             ///< Tab. 2 left: partial + clipped Gaussian noise
    kDensity,            ///< Tab. 2 right: partial, target thinned to `density_keep` and refilled
    kComplete,           ///< Supp. c2c: no crop, noise
    kCompleteToPartial,  ///< Supp. c2p: source cropped, target complete, noise
    kOverlapSweep,       ///< Supp. overlap: crop ratios from `sweep_keeps`, noise
    kIndoor,             ///< Tab. 3: scan point clouds (2048 points), cropped, no noise
};

/// How the rigid motion is drawn.
enum class MotionConvention {
    kEuler,      ///< paper: angles U[0, max] about x, y, z, R = Rx Ry Rz; t U[-max, max] per axis
    kAxisAngle,  ///< authors' code: uniform axis, angle U[0, max]; t = uniform dir * U[0, max]
};

/// Where the two clouds come from.
enum class Pairing {
    kIndependent,  ///< paper: two independent samples; motion on the target; labels by eta
    kShared,       ///< authors' code: crops of one sample; motion on the source; labels by index
    /// The dataset file's own source, target and transform (ICL-NUIM's test file, as DeepGMR's
    /// and the OGMM authors' evaluation use it): no resampling, crop, motion or noise; the
    /// first `points` points of each stored cloud; labels by eta.
    kStored,
};

std::string ToString(Protocol p);
std::string ToString(MotionConvention m);
std::string ToString(Pairing p);
/// Parsers throw std::invalid_argument naming the value and listing the known ones.
Protocol ParseProtocol(const std::string& name);
MotionConvention ParseMotionConvention(const std::string& name);
Pairing ParsePairing(const std::string& name);
/// Every protocol name, in declaration order.
std::vector<std::string> ProtocolNames();
/// The enums in JSON by name; reading one is strict (the parsers above), where nlohmann's enum
/// macro would map an unknown name to the first value.
void to_json(nlohmann::json& j, Protocol p);
void from_json(const nlohmann::json& j, Protocol& p);
void to_json(nlohmann::json& j, MotionConvention m);
void from_json(const nlohmann::json& j, MotionConvention& m);
void to_json(nlohmann::json& j, Pairing p);
void from_json(const nlohmann::json& j, Pairing& p);

struct ProtocolOptions {
    Protocol protocol = Protocol::kPartial;  ///< which protocol
    int points = 1024;          ///< points sampled per cloud before cropping (indoor: 2048)
    double keep = 0.7;          ///< crop keep ratio in (0, 1]: round(keep * points) survive
    double noise_sigma = 0.01;  ///< jitter std-dev per coordinate (protocols with noise)
    double noise_clip = 0.05;   ///< jitter clipped to [-clip, clip]
    MotionConvention motion = MotionConvention::kEuler;  ///< motion convention
    double max_rotation_deg = 45.0;  ///< Euler: per-axis max angle; axis-angle: max angle [deg]
    double max_translation = 0.5;    ///< Euler: per-axis half-range; axis-angle: max length
    Pairing pairing = Pairing::kIndependent;  ///< independent samples or one shared sample
    double eta = 0.1;  ///< overlap radius for labels (paper eta = 0.1); used by independent pairs
    double density_keep = 0.5;  ///< density: fraction of target points kept distinct
    /// overlap-sweep crop ratios, aiming at ~30/40/50/60/70% overlap. Measured mean source
    /// overlap on the embedded corpus (420 pairs per level): independent pairing (eta 0.1)
    /// 0.35, 0.42, 0.52, 0.60, 0.71; shared pairing 0.30, 0.40, 0.44, 0.55, 0.67.
    std::vector<double> sweep_keeps = {0.25, 0.35, 0.45, 0.55, 0.65};
};

/// Every field under its own name (a pair file's provenance "params", a training bundle's
/// "protocol"); reading needs every key: ProtocolOptionsFromJson reads a partial object.
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(ProtocolOptions, protocol, points, keep, noise_sigma, noise_clip,
                                   motion, max_rotation_deg, max_translation, pairing, eta,
                                   density_keep, sweep_keeps)
/// The keys `j` gives over `base`, or over the defaults of the protocol `j` names
/// (DefaultProtocolOptions). Unknown keys, wrong JSON types, fractional values of integer keys
/// and unknown names throw std::invalid_argument naming the key (ParseConfig's rules, as model
/// and training configs); ranges are ValidateProtocolOptions'.
ProtocolOptions ProtocolOptionsFromJson(const nlohmann::json& j, const ProtocolOptions& base);

/// Paper defaults for `p` (indoor samples 2048 points, every other protocol 1024).
ProtocolOptions DefaultProtocolOptions(Protocol p);
/// Throws std::invalid_argument naming the first impossible parameter (keep outside (0, 1],
/// points < 3, a crop leaving < 3 points, negative noise, eta <= 0, ...).
void ValidateProtocolOptions(const ProtocolOptions& o);
/// True for the protocols that jitter both clouds.
bool ProtocolAddsNoise(Protocol p);
/// How a crop turns keep * n into a point count.
enum class CropRounding {
    kNearest,  ///< round(keep * n): 717 of 1024 at 0.7, as the ModelNet protocols keep
    kFloor,    ///< floor(keep * n): 1433 of 2048 at 0.7, as the authors' indoor code keeps
};
/// The rounding the protocol's crops use (kFloor for indoor, kNearest otherwise).
CropRounding CropRoundingFor(Protocol p);
/// Number of points a crop with ratio `keep` leaves of n.
Eigen::Index CropCount(Eigen::Index n, double keep, CropRounding rounding = CropRounding::kNearest);

// ---- Building blocks (each uses only the rng it is given) ----

/// Uniform unit vector: phi ~ U[0, 2 pi), cos(theta) ~ U[-1, 1].
Eigen::Vector3d RandomUnitVector(std::mt19937_64& rng);
/// Indices (ascending) of the CropCount(n, keep) points with the largest signed distance to the
/// centroid along a uniformly random direction, i.e. those above the (1 - keep) quantile.
/// Ties broken by index. keep = 1 returns every index and draws nothing.
std::vector<Eigen::Index> CropIndices(const PointCloud& cloud, double keep, std::mt19937_64& rng,
                                      CropRounding rounding = CropRounding::kNearest);
/// Rigid motion drawn with `convention` (see MotionConvention).
Transform DrawMotion(MotionConvention convention, double max_rotation_deg, double max_translation,
                     std::mt19937_64& rng);
/// Adds clip(sigma * N(0, 1), -clip, clip) to every coordinate; sigma = 0 draws nothing.
void AddClippedNoise(PointCloud& cloud, double sigma, double clip, std::mt19937_64& rng);
/// Density thinning: a random round(keep * n) of the n indices stay distinct and are repeated
/// cyclically back to n entries. Returns, for each output point, its input index.
std::vector<Eigen::Index> ThinAndRepeat(Eigen::Index n, double keep, std::mt19937_64& rng);
/// In-place uniform shuffle (Fisher-Yates with UniformIndex).
void Shuffle(std::vector<Eigen::Index>& v, std::mt19937_64& rng);
/// Rows of `cloud` at `index`.
PointCloud Gather(const PointCloud& cloud, const std::vector<Eigen::Index>& index);

/// Overlap labels by radius: a source point overlaps when its nearest target point, after
/// T_gt, is closer than eta; a target point when its nearest moved source point is. Sets the
/// labels and the ratios of `pair`.
void LabelOverlapByRadius(Pair& pair, double eta);

// ---- Pairs ----

/// Pair `pair_index` of a benchmark with seed `seed`, drawn from MakePairRng(seed, pair_index)
/// only (the stored pairing draws nothing; it throws std::invalid_argument naming the shape
/// when the shape stores no pair). The shape is shapes[(pair_index / L) % shapes.size()] and the
/// overlap-sweep level pair_index % L (L = number of sweep levels, 1 for other protocols), so pair
/// k never depends on how many pairs are generated. `options` must be valid
/// (ValidateProtocolOptions).
Pair GeneratePair(const std::vector<ShapeSource>& shapes, const ProtocolOptions& options,
                  std::uint64_t seed, std::uint64_t pair_index);

/// Number of pair levels: the overlap-sweep's keep ratios, 1 for every other protocol. Pair k
/// uses level k % levels and shape (k / levels) % shapes, so levels * shapes pairs use every
/// shape once per level (`generate --pairs all`).
std::size_t ProtocolLevels(const ProtocolOptions& options);

/// Called after each generated pair with (done, total).
using ProgressCallback = std::function<void(std::size_t, std::size_t)>;

/// Pairs 0 .. num_pairs-1 (validates first; throws std::invalid_argument before any work).
/// provenance = ProtocolProvenance(options) plus {"seed", "num_pairs", "num_shapes"}.
PairSet GeneratePairs(const std::vector<ShapeSource>& shapes, const ProtocolOptions& options,
                      std::uint64_t seed, std::size_t num_pairs,
                      const ProgressCallback& progress = nullptr);

/// {"protocol", "params" (every option), "pairing", "noise_sigma" (0 when the protocol adds
/// none), "overlap_labels": "radius" | "shared-index"}; stored pairing adds "stored_pairs"
/// saying which parameters were not applied.
nlohmann::json ProtocolProvenance(const ProtocolOptions& options);

}  // namespace regbench
