#include "protocols/generate.hpp"

#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "core/atomic_file.hpp"
#include "core/metrics.hpp"
#include "core/usage_error.hpp"
#include "protocols/pair_file.hpp"
#include "protocols/pair_hash.hpp"

namespace regbench {

double MeasuredSourceRadius(const PairSet& set) {
    std::vector<const PointCloud*> sources;
    sources.reserve(set.pairs.size());
    for (const Pair& pair : set.pairs) sources.push_back(&pair.source);
    return MedianCloudRadius(sources);
}

ProtocolOptions ScaledProtocolOptions(ProtocolOptions options, double scale) {
    options.max_translation *= scale;
    options.noise_sigma *= scale;
    options.noise_clip *= scale;
    options.eta *= scale;
    return options;
}

namespace {

/// `value` with 3 significant digits, as the refusal suggests it for --scale.
std::string ThreeDigits(double value) {
    std::ostringstream out;
    out.precision(3);
    out << value;
    return out.str();
}

/// UsageError when the clouds' measured radius is far from what `scale` says.
void CheckMeasuredScale(const GenerateRequest& request, double radius) {
    if (!std::isfinite(radius)) return;  // no points: nothing to measure
    const double ratio = radius / request.scale;
    if (ratio <= kScaleTolerance && ratio >= 1.0 / kScaleTolerance) return;
    const ProtocolOptions& o = request.options;
    const std::string noise = ProtocolAddsNoise(o.protocol)
                                  ? ", noise sigma " + ThreeDigits(o.noise_sigma * request.scale)
                                  : std::string();
    throw UsageError(
        "generate: the clouds of '" + request.dataset + "' have radius " + ThreeDigits(radius) +
        " (median over the pairs of the source's largest distance from its centroid), but the "
        "protocol's lengths (translation up to " +
        ThreeDigits(o.max_translation * request.scale) + noise + ", overlap radius eta " +
        ThreeDigits(o.eta * request.scale) + ") are for clouds of radius " +
        ThreeDigits(request.scale) + ": pass --scale " + ThreeDigits(radius) +
        " to multiply them by the data's size (or rescale the data into the unit sphere)");
}

}  // namespace

void CheckGenerateRequest(const GenerateRequest& request) {
    if (!std::isfinite(request.scale) || request.scale <= 0.0) {
        throw std::invalid_argument("generate: --scale must be a finite number > 0");
    }
    ValidateProtocolOptions(ScaledProtocolOptions(request.options, request.scale));
    if (!request.one_per_item && request.num_pairs < 1)
        throw std::invalid_argument("generate: --pairs must be >= 1");
    if (request.num_pairs > kMaxGeneratedPairs) {
        throw std::invalid_argument("generate: --pairs " + std::to_string(request.num_pairs) +
                                    " is more than the supported " +
                                    std::to_string(kMaxGeneratedPairs));
    }
}

void GenerateToFile(const GenerateRequest& request, const ShapeLoader& load_shapes,
                    const ProgressCallback& progress) {
    CheckGenerateRequest(request);
    if (request.out.empty()) throw std::invalid_argument("generate: --out is required");
    const std::filesystem::path out(request.out);
    const std::filesystem::path dir = out.has_parent_path() ? out.parent_path() : ".";
    if (!std::filesystem::is_directory(dir)) {
        throw std::invalid_argument(request.out + ": output directory " + dir.string() +
                                    " does not exist");
    }
    CheckOutputPath(request.out);  // not a directory or device; before any work
    if (!load_shapes) throw std::invalid_argument("generate: no shape loader");
    const std::vector<ShapeSource> shapes = load_shapes(request.dataset, request.split);
    if (shapes.empty()) {
        throw std::runtime_error("dataset '" + request.dataset + "' split '" + request.split +
                                 "' has no shapes");
    }
    // One per item: shape k / levels at level k % levels covers every (item, level) once.
    const std::size_t num_pairs =
        request.one_per_item ? shapes.size() * ProtocolLevels(request.options) : request.num_pairs;
    if (num_pairs > kMaxGeneratedPairs) {
        throw std::invalid_argument("generate: --pairs all would make " +
                                    std::to_string(num_pairs) + " pairs, more than the supported " +
                                    std::to_string(kMaxGeneratedPairs));
    }
    PairSet set = GeneratePairs(shapes, ScaledProtocolOptions(request.options, request.scale),
                                request.seed, num_pairs, progress);
    const double radius = MeasuredSourceRadius(set);
    CheckMeasuredScale(request, radius);
    set.provenance["scale"] = request.scale;
    if (std::isfinite(radius)) set.provenance["source_radius"] = radius;
    set.provenance["pair_selection"] = request.one_per_item ? "one-per-item" : "cycle";
    set.provenance["dataset"] = request.dataset;
    set.provenance["split"] = request.split;
    for (const auto& item : request.extra_provenance.items()) {
        set.provenance[item.key()] = item.value();
    }
    // Rows computed on these pairs carry this hash, so reports can tell pair files apart.
    set.provenance["content_hash"] = PairSetContentHash(set);
    WritePairFile(request.out, set);
}

}  // namespace regbench
