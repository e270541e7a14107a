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
    std::string out;          ///< output HDF5 path
    /// Extra provenance merged in verbatim (e.g. {"regbench_version", "git_sha"}). Must not hold
    /// anything time- or machine-dependent: the same request must give byte-identical files.
    nlohmann::json extra_provenance = nlohmann::json::object();
};

/// The most pairs one file may hold: a pair file is held in memory while it is written, and 10
/// million 1024-point pairs are already ~330 GB, so more is a typo, not a benchmark.
inline constexpr std::size_t kMaxGeneratedPairs = 10000000;

/// The request's numbers, before any work: ValidateProtocolOptions and --pairs in
/// [1, kMaxGeneratedPairs] (unless one_per_item). Throws std::invalid_argument naming the value;
/// `regbench generate` reports it as a usage error.
void CheckGenerateRequest(const GenerateRequest& request);

/// Checks the request (options, num_pairs >= 1, output directory exists) before any work, then
/// loads the shapes, generates the pairs and writes `out` atomically. On any failure nothing is
/// left at `out` (an existing file there is not replaced). Provenance: ProtocolProvenance plus
/// seed, num_pairs, num_shapes, dataset, split, pair_selection ("one-per-item" for
/// one_per_item, else "cycle": pair k uses item k mod items) and extra_provenance.
void GenerateToFile(const GenerateRequest& request, const ShapeLoader& load_shapes,
                    const ProgressCallback& progress = nullptr);

}  // namespace regbench
