#pragma once
// `regbench generate` as a library call: validate, load shapes, generate pairs, write one file.
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "protocols/pair_protocols.hpp"
#include "protocols/shape_source.hpp"

namespace regbench {

/// Loads the shapes of (dataset, split). Throws std::runtime_error naming the dataset or path.
using ShapeLoader =
    std::function<std::vector<ShapeSource>(const std::string& dataset, const std::string& split)>;

struct GenerateRequest {
    std::string dataset = "cgal";  ///< dataset name (the embedded corpus is "cgal")
    std::string split = "test";    ///< dataset split
    std::size_t num_pairs = 0;     ///< pairs to generate, >= 1 (ignored when one_per_item)
    /// `--pairs all`: one pair per item of the split (per overlap-sweep level), i.e.
    /// items * ProtocolLevels pairs, so every item is used exactly once per level.
    bool one_per_item = false;
    std::uint64_t seed = 0;   ///< benchmark seed: pair k uses MakePairRng(seed, k)
    ProtocolOptions options;  ///< protocol and its parameters
    /// The data's size in units of the paper's unit-sphere objects (`generate --scale`): the
    /// protocol's lengths (max_translation, noise_sigma, noise_clip, eta) are multiplied by it;
    /// 1 leaves the paper's protocol as it is, bit for bit.
    double scale = 1.0;
    std::string out;  ///< output HDF5 path
    /// Extra provenance merged in verbatim (e.g. {"regbench_version", "git_sha"}). Must not hold
    /// anything time- or machine-dependent: the same request must give byte-identical files.
    nlohmann::json extra_provenance = nlohmann::json::object();
};

/// The most pairs one file may hold: a pair file is held in memory while it is written, and 10
/// million 1024-point pairs are already ~330 GB, so more is a typo, not a benchmark.
inline constexpr std::size_t kMaxGeneratedPairs = 10000000;

/// How far the clouds' measured radius (MeasuredSourceRadius) may lie from `scale` (a factor,
/// either way) before generate refuses: the protocol's lengths would not mean what they say.
inline constexpr double kScaleTolerance = 10.0;

/// The clouds' size as generate measures it: the median over the pairs of the source's radius
/// (largest distance of a source point from the source's centroid); NaN for no pairs.
double MeasuredSourceRadius(const PairSet& set);

/// `options` with its lengths (max_translation, noise_sigma, noise_clip, eta) times `scale`.
ProtocolOptions ScaledProtocolOptions(ProtocolOptions options, double scale);

/// The request's numbers, before any work: ValidateProtocolOptions and --pairs in
/// [1, kMaxGeneratedPairs] (unless one_per_item). Throws std::invalid_argument naming the value;
/// `regbench generate` reports it as a usage error.
void CheckGenerateRequest(const GenerateRequest& request);

/// Checks the request (options, num_pairs >= 1, output directory exists) before any work, then
/// loads the shapes, generates the pairs (options scaled by `scale`) and writes `out`
/// atomically. When the measured radius (MeasuredSourceRadius) is more than kScaleTolerance
/// times above or below `scale`, nothing is written: UsageError naming the radius and the
/// `--scale` that fits. On any failure nothing is left at `out` (an existing file there is not
/// replaced). Provenance: ProtocolProvenance (of the scaled options) plus seed, num_pairs,
/// num_shapes, dataset, split, pair_selection ("one-per-item" for one_per_item, else "cycle":
/// pair k uses item k mod items), scale, source_radius and extra_provenance.
void GenerateToFile(const GenerateRequest& request, const ShapeLoader& load_shapes,
                    const ProgressCallback& progress = nullptr);

}  // namespace regbench
