#include "protocols/pair_protocols.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <utility>

#include "core/coordinate_limit.hpp"
#include "core/enum_names.hpp"
#include "core/kd_tree.hpp"
#include "core/math_constants.hpp"
#include "core/params.hpp"
#include "core/rng.hpp"
#include "core/transform.hpp"

namespace regbench {
namespace {

/// Fewest points a cropped cloud may keep: registration needs three non-collinear points.
constexpr Eigen::Index kMinCloudPoints = 3;
/// Indoor (Tab. 3) samples 2048 points per scan; the ModelNet protocols 1024.
constexpr int kIndoorPoints = 2048;

constexpr EnumName<Protocol> kProtocolNames[] = {
    {Protocol::kPartial, "partial"},
    {Protocol::kJitter, "jitter"},
    {Protocol::kDensity, "density"},
    {Protocol::kComplete, "complete"},
    {Protocol::kCompleteToPartial, "complete-to-partial"},
    {Protocol::kOverlapSweep, "overlap-sweep"},
    {Protocol::kIndoor, "indoor"},
};
constexpr EnumName<MotionConvention> kMotionNames[] = {
    {MotionConvention::kEuler, "euler"},
    {MotionConvention::kAxisAngle, "axis-angle"},
};
constexpr EnumName<Pairing> kPairingNames[] = {
    {Pairing::kIndependent, "independent"},
    {Pairing::kShared, "shared"},
    {Pairing::kStored, "stored"},
};

void Require(bool ok, const std::string& name, const std::string& why) {
    if (!ok) throw std::invalid_argument("protocol parameter '" + name + "' " + why);
}

/// Crop keep ratios of (source, target) for `o` at overlap-sweep level `level`.
std::pair<double, double> KeepRatios(const ProtocolOptions& o, std::size_t level) {
    switch (o.protocol) {
        case Protocol::kComplete:
            return {1.0, 1.0};
        case Protocol::kCompleteToPartial:
            return {o.keep, 1.0};
        case Protocol::kOverlapSweep:
            return {o.sweep_keeps[level], o.sweep_keeps[level]};
        default:
            return {o.keep, o.keep};
    }
}

double Fraction(const Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1>& labels) {
    if (labels.size() == 0) return 0.0;
    return labels.cast<double>().sum() / static_cast<double>(labels.size());
}

/// The protocol's clipped Gaussian noise, source first then target, if it adds any.
void AddProtocolNoise(Pair& pair, const ProtocolOptions& o, std::mt19937_64& rng) {
    if (!ProtocolAddsNoise(o.protocol)) return;
    AddClippedNoise(pair.source, o.noise_sigma, o.noise_clip, rng);
    AddClippedNoise(pair.target, o.noise_sigma, o.noise_clip, rng);
}

/// Paper pairing: two independent samples, each cropped; the motion moves the target.
/// Draw order: source sample, target sample, source crop, target crop, density, motion, noise.
Pair IndependentPair(const ShapeSource& shape, const ProtocolOptions& o, double keep_source,
                     double keep_target, std::mt19937_64& rng) {
    const PointCloud source_full = shape.Sample(o.points, rng);
    const PointCloud target_full = shape.Sample(o.points, rng);
    Pair pair;
    const CropRounding rounding = CropRoundingFor(o.protocol);
    pair.source = Gather(source_full, CropIndices(source_full, keep_source, rng, rounding));
    PointCloud target = Gather(target_full, CropIndices(target_full, keep_target, rng, rounding));
    if (o.protocol == Protocol::kDensity) {
        target = Gather(target, ThinAndRepeat(target.rows(), o.density_keep, rng));
    }
    pair.T_gt = DrawMotion(o.motion, o.max_rotation_deg, o.max_translation, rng);
    pair.target = Apply(pair.T_gt, target);
    AddProtocolNoise(pair, o, rng);
    LabelOverlapByRadius(pair, o.eta);
    return pair;
}

Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> SurvivesIn(const std::vector<Eigen::Index>& index,
                                                          const std::vector<char>& kept_other) {
    Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> labels(static_cast<Eigen::Index>(index.size()));
    for (std::size_t i = 0; i < index.size(); ++i) {
        labels(static_cast<Eigen::Index>(i)) =
            kept_other[static_cast<std::size_t>(index[i])] ? 1 : 0;
    }
    return labels;
}

std::vector<char> Membership(const std::vector<Eigen::Index>& index, Eigen::Index n) {
    std::vector<char> in(static_cast<std::size_t>(n), 0);
    for (Eigen::Index i : index) in[static_cast<std::size_t>(i)] = 1;
    return in;
}

/// Authors' pairing (ogmm.md section 4): both clouds are crops of one sample; a point overlaps
/// iff the same sample point survives the other crop; the motion moves the source, so the
/// ground truth is its inverse; both are shuffled, then jittered.
/// Draw order: sample, source crop, target crop, density, source shuffle, target shuffle,
/// motion, noise.
Pair SharedPair(const ShapeSource& shape, const ProtocolOptions& o, double keep_source,
                double keep_target, std::mt19937_64& rng) {
    const PointCloud full = shape.Sample(o.points, rng);
    const CropRounding rounding = CropRoundingFor(o.protocol);
    std::vector<Eigen::Index> source_index = CropIndices(full, keep_source, rng, rounding);
    std::vector<Eigen::Index> target_index = CropIndices(full, keep_target, rng, rounding);
    const std::vector<char> in_source = Membership(source_index, full.rows());
    const std::vector<char> in_target = Membership(target_index, full.rows());
    if (o.protocol == Protocol::kDensity) {
        const std::vector<Eigen::Index> thin =
            ThinAndRepeat(static_cast<Eigen::Index>(target_index.size()), o.density_keep, rng);
        std::vector<Eigen::Index> repeated(thin.size());
        for (std::size_t i = 0; i < thin.size(); ++i) {
            repeated[i] = target_index[static_cast<std::size_t>(thin[i])];
        }
        target_index = std::move(repeated);
    }
    Shuffle(source_index, rng);
    Shuffle(target_index, rng);
    const Transform motion = DrawMotion(o.motion, o.max_rotation_deg, o.max_translation, rng);
    Pair pair;
    pair.source = Apply(motion, Gather(full, source_index));
    pair.target = Gather(full, target_index);
    pair.T_gt = InvertRigid(motion);
    AddProtocolNoise(pair, o, rng);
    pair.source_overlap = SurvivesIn(source_index, in_target);
    pair.target_overlap = SurvivesIn(target_index, in_source);
    pair.source_overlap_ratio = Fraction(pair.source_overlap);
    pair.target_overlap_ratio = Fraction(pair.target_overlap);
    return pair;
}

/// Stored pairing: the dataset file's own source, target and transform, cut to their first
/// `points` points as DeepGMR's loader slices [:n_points] (all of a shorter cloud). Nothing is
/// drawn: the pair is the file's, whatever the seed.
Pair StoredPair(const ShapeSource& shape, const ProtocolOptions& o) {
    if (!shape.has_stored_pair()) {
        throw std::invalid_argument(
            "pairing 'stored' needs pairs stored in the dataset file (source, target and "
            "transform, e.g. ICL-NUIM's test/icl_nuim.h5); shape '" +
            shape.name() + "' stores none");
    }
    const auto first = [&](const PointCloud& c) -> PointCloud {
        return c.topRows(std::min<Eigen::Index>(c.rows(), o.points));
    };
    Pair pair;
    pair.source = first(shape.stored_source());
    pair.target = first(shape.stored_target());
    pair.T_gt = shape.stored_transform();
    LabelOverlapByRadius(pair, o.eta);
    return pair;
}

}  // namespace

std::size_t ProtocolLevels(const ProtocolOptions& o) {
    return o.protocol == Protocol::kOverlapSweep ? o.sweep_keeps.size() : 1;
}

std::string ToString(Protocol p) { return EnumToString(kProtocolNames, p); }
std::string ToString(MotionConvention m) { return EnumToString(kMotionNames, m); }
std::string ToString(Pairing p) { return EnumToString(kPairingNames, p); }
Protocol ParseProtocol(const std::string& name) {
    return ParseEnum(kProtocolNames, "protocol", name);
}
MotionConvention ParseMotionConvention(const std::string& name) {
    return ParseEnum(kMotionNames, "motion convention", name);
}
Pairing ParsePairing(const std::string& name) { return ParseEnum(kPairingNames, "pairing", name); }

std::vector<std::string> ProtocolNames() {
    std::vector<std::string> names;
    for (const auto& e : kProtocolNames) names.emplace_back(e.name);
    return names;
}

void to_json(nlohmann::json& j, Protocol p) { j = ToString(p); }
void from_json(const nlohmann::json& j, Protocol& p) { p = ParseProtocol(j.get<std::string>()); }
void to_json(nlohmann::json& j, MotionConvention m) { j = ToString(m); }
void from_json(const nlohmann::json& j, MotionConvention& m) {
    m = ParseMotionConvention(j.get<std::string>());
}
void to_json(nlohmann::json& j, Pairing p) { j = ToString(p); }
void from_json(const nlohmann::json& j, Pairing& p) { p = ParsePairing(j.get<std::string>()); }

ProtocolOptions ProtocolOptionsFromJson(const nlohmann::json& j, const ProtocolOptions& base) {
    if (j.is_null()) return base;
    if (!j.is_object()) {
        throw std::invalid_argument("protocol options must be a JSON object, got " + j.dump());
    }
    const bool names_protocol = j.contains("protocol") && j["protocol"].is_string();
    nlohmann::json merged =
        names_protocol ? DefaultProtocolOptions(ParseProtocol(j["protocol"])) : base;
    merged.update(j);
    return ParseConfig<ProtocolOptions>(merged, "protocol options");
}

ProtocolOptions DefaultProtocolOptions(Protocol p) {
    ProtocolOptions o;
    o.protocol = p;
    if (p == Protocol::kIndoor) o.points = kIndoorPoints;
    return o;
}

bool ProtocolAddsNoise(Protocol p) {
    return p == Protocol::kJitter || p == Protocol::kComplete ||
           p == Protocol::kCompleteToPartial || p == Protocol::kOverlapSweep;
}

CropRounding CropRoundingFor(Protocol p) {
    return p == Protocol::kIndoor ? CropRounding::kFloor : CropRounding::kNearest;
}

Eigen::Index CropCount(Eigen::Index n, double keep, CropRounding rounding) {
    const double x = keep * static_cast<double>(n);
    return static_cast<Eigen::Index>(rounding == CropRounding::kFloor ? std::floor(x)
                                                                      : std::round(x));
}

void ValidateProtocolOptions(const ProtocolOptions& o) {
    Require(o.points >= kMinCloudPoints, "points", "must be >= 3, got " + std::to_string(o.points));
    const auto check_keep = [&](double keep, const std::string& name) {
        Require(std::isfinite(keep) && keep > 0.0 && keep <= 1.0, name,
                "must be in (0, 1], got " + std::to_string(keep));
        Require(CropCount(o.points, keep) >= kMinCloudPoints, name,
                "leaves " + std::to_string(CropCount(o.points, keep)) + " of " +
                    std::to_string(o.points) + " points; at least 3 are needed");
    };
    check_keep(o.keep, "keep");
    Require(std::isfinite(o.noise_sigma) && o.noise_sigma >= 0.0, "noise_sigma", "must be >= 0");
    // Every offset is clamped to the clip: with the translation's 5e14 it keeps the clouds
    // within the coordinate limit (a clip of 1e18 wrote a file `inspect` then refused).
    Require(std::isfinite(o.noise_clip) && o.noise_clip >= 0.0 &&
                o.noise_clip <= kMaxCoordinate / 4,
            "noise_clip",
            "must be in [0, 2.5e14] (clouds must stay within the coordinate limit |x| <= 1e15)");
    Require(std::isfinite(o.max_rotation_deg) && o.max_rotation_deg >= 0.0 &&
                o.max_rotation_deg <= 180.0,
            "max_rotation_deg", "must be in [0, 180]");
    Require(std::isfinite(o.max_translation) && o.max_translation >= 0.0 &&
                o.max_translation <= kMaxCoordinate / 2,
            "max_translation",
            "must be in [0, 5e14] (clouds must stay within the coordinate limit |x| <= 1e15)");
    Require(std::isfinite(o.eta) && o.eta > 0.0, "eta", "must be > 0");
    Require(std::isfinite(o.density_keep) && o.density_keep > 0.0 && o.density_keep <= 1.0,
            "density_keep", "must be in (0, 1]");
    if (o.protocol == Protocol::kOverlapSweep) {
        Require(!o.sweep_keeps.empty(), "sweep_keeps", "must list at least one keep ratio");
        for (double k : o.sweep_keeps) check_keep(k, "sweep_keeps");
        // Stored pairs have no crop to sweep: every level would repeat the same pair.
        Require(o.pairing != Pairing::kStored, "pairing",
                "'stored' cannot sweep overlap (the stored pairs are not cropped)");
    }
}

Eigen::Vector3d RandomUnitVector(std::mt19937_64& rng) {
    const double phi = UniformReal(rng, 0.0, 2.0 * kPi);
    const double cos_theta = UniformReal(rng, -1.0, 1.0);
    const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
    return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}

std::vector<Eigen::Index> CropIndices(const PointCloud& cloud, double keep, std::mt19937_64& rng,
                                      CropRounding rounding) {
    const Eigen::Index n = cloud.rows();
    std::vector<Eigen::Index> index(static_cast<std::size_t>(n));
    std::iota(index.begin(), index.end(), Eigen::Index{0});
    if (keep >= 1.0) return index;
    const Eigen::Vector3d direction = RandomUnitVector(rng);
    const Eigen::RowVector3d centroid = cloud.colwise().mean();
    const Eigen::VectorXd signed_distance = (cloud.rowwise() - centroid) * direction;
    // Keep the m largest projections: those above the (1 - keep) quantile.
    const auto m =
        static_cast<std::size_t>(std::clamp<Eigen::Index>(CropCount(n, keep, rounding), 0, n));
    std::partial_sort(index.begin(), index.begin() + static_cast<std::ptrdiff_t>(m), index.end(),
                      [&](Eigen::Index a, Eigen::Index b) {
                          if (signed_distance(a) != signed_distance(b)) {
                              return signed_distance(a) > signed_distance(b);
                          }
                          return a < b;
                      });
    index.resize(m);
    std::sort(index.begin(), index.end());
    return index;
}

Transform DrawMotion(MotionConvention convention, double max_rotation_deg, double max_translation,
                     std::mt19937_64& rng) {
    if (convention == MotionConvention::kEuler) {
        // Paper: three angles U[0, max], R = Rx * Ry * Rz; t ~ U[-max_t, max_t]^3.
        const double x = UniformReal(rng, 0.0, max_rotation_deg);
        const double y = UniformReal(rng, 0.0, max_rotation_deg);
        const double z = UniformReal(rng, 0.0, max_rotation_deg);
        Eigen::Vector3d t;
        for (int i = 0; i < 3; ++i) t(i) = UniformReal(rng, -max_translation, max_translation);
        return MakeTransform(RotationXyzProductDeg(x, y, z), t);
    }
    // Authors' code: uniform axis, angle U[0, max]; translation uniform direction * U[0, max_t].
    const Eigen::Vector3d axis = RandomUnitVector(rng);
    const double angle_rad = UniformReal(rng, 0.0, max_rotation_deg) * kPi / 180.0;
    const Eigen::Vector3d direction = RandomUnitVector(rng);
    const double length = UniformReal(rng, 0.0, max_translation);
    return MakeTransform(RotationFromAxisAngle(axis, angle_rad), direction * length);
}

void AddClippedNoise(PointCloud& cloud, double sigma, double clip, std::mt19937_64& rng) {
    if (sigma <= 0.0) return;
    for (Eigen::Index i = 0; i < cloud.rows(); ++i) {
        for (int d = 0; d < 3; ++d) {
            cloud(i, d) += std::clamp(sigma * StandardNormal(rng), -clip, clip);
        }
    }
}

void Shuffle(std::vector<Eigen::Index>& v, std::mt19937_64& rng) {
    for (std::size_t i = v.size(); i > 1; --i) {
        const auto j = static_cast<std::size_t>(UniformIndex(rng, i));
        std::swap(v[i - 1], v[j]);
    }
}

std::vector<Eigen::Index> ThinAndRepeat(Eigen::Index n, double keep, std::mt19937_64& rng) {
    std::vector<Eigen::Index> order(static_cast<std::size_t>(n));
    std::iota(order.begin(), order.end(), Eigen::Index{0});
    if (n == 0) return order;
    Shuffle(order, rng);
    const auto m = static_cast<std::size_t>(std::clamp<Eigen::Index>(CropCount(n, keep), 1, n));
    std::vector<Eigen::Index> out(static_cast<std::size_t>(n));
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = order[i % m];
    return out;
}

PointCloud Gather(const PointCloud& cloud, const std::vector<Eigen::Index>& index) {
    PointCloud out(static_cast<Eigen::Index>(index.size()), 3);
    for (std::size_t i = 0; i < index.size(); ++i) {
        out.row(static_cast<Eigen::Index>(i)) = cloud.row(index[i]);
    }
    return out;
}

void LabelOverlapByRadius(Pair& pair, double eta) {
    const PointCloud moved_source = Apply(pair.T_gt, pair.source);
    const KdTree target_tree(pair.target);
    const KdTree source_tree(moved_source);
    pair.source_overlap =
        (NearestDistances(target_tree, moved_source).array() < eta).cast<std::uint8_t>();
    pair.target_overlap =
        (NearestDistances(source_tree, pair.target).array() < eta).cast<std::uint8_t>();
    pair.source_overlap_ratio = Fraction(pair.source_overlap);
    pair.target_overlap_ratio = Fraction(pair.target_overlap);
}

Pair GeneratePair(const std::vector<ShapeSource>& shapes, const ProtocolOptions& options,
                  std::uint64_t seed, std::uint64_t pair_index) {
    if (shapes.empty()) throw std::invalid_argument("no shapes to generate pairs from");
    const std::size_t levels = ProtocolLevels(options);
    const auto level = static_cast<std::size_t>(pair_index % levels);
    const ShapeSource& shape =
        shapes[static_cast<std::size_t>((pair_index / levels) % shapes.size())];
    const auto [keep_source, keep_target] = KeepRatios(options, level);
    Pair pair;
    if (options.pairing == Pairing::kStored) {
        pair = StoredPair(shape, options);
        pair.meta = {{"stored", true}};
    } else {
        std::mt19937_64 rng = MakePairRng(seed, pair_index);
        pair = options.pairing == Pairing::kShared
                   ? SharedPair(shape, options, keep_source, keep_target, rng)
                   : IndependentPair(shape, options, keep_source, keep_target, rng);
        pair.meta = {{"source_keep", keep_source}, {"target_keep", keep_target}};
    }
    pair.shape = shape.name();
    pair.category = shape.category();
    return pair;
}

nlohmann::json ProtocolProvenance(const ProtocolOptions& options) {
    const bool stored = options.pairing == Pairing::kStored;
    const bool noise = ProtocolAddsNoise(options.protocol) && !stored;
    // `params` lists what the pairs were made with: stored pairs are the file's own (no
    // protocol, only `points` and the overlap radius), and a protocol without noise carries no
    // noise parameters, so a reader (and `inspect`) sees one noise_sigma, the applied one.
    nlohmann::json params = options;
    if (stored) {
        params = {{"points", options.points}, {"pairing", "stored"}, {"eta", options.eta}};
    } else if (!noise) {
        params.erase("noise_sigma");
        params.erase("noise_clip");
    }
    nlohmann::json j = {
        {"protocol", stored ? std::string("stored") : ToString(options.protocol)},
        {"params", params},
        {"pairing", ToString(options.pairing)},
        {"noise_sigma", noise ? options.noise_sigma : 0.0},
        {"overlap_labels", options.pairing == Pairing::kShared ? "shared-index" : "radius"}};
    if (stored) {
        j["stored_pairs"] =
            "source, target and transform as stored in the dataset file (first `points` points "
            "of each cloud); crop, motion and noise parameters not applied";
    }
    return j;
}

PairSet GeneratePairs(const std::vector<ShapeSource>& shapes, const ProtocolOptions& options,
                      std::uint64_t seed, std::size_t num_pairs, const ProgressCallback& progress) {
    ValidateProtocolOptions(options);
    if (shapes.empty()) throw std::invalid_argument("no shapes to generate pairs from");
    PairSet set;
    set.provenance = ProtocolProvenance(options);
    set.provenance["seed"] = seed;
    set.provenance["num_pairs"] = num_pairs;
    set.provenance["num_shapes"] = shapes.size();
    set.pairs.reserve(num_pairs);
    for (std::size_t k = 0; k < num_pairs; ++k) {
        set.pairs.push_back(GeneratePair(shapes, options, seed, k));
        if (progress) progress(k + 1, num_pairs);
    }
    return set;
}

}  // namespace regbench
