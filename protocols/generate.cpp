#include "protocols/generate.hpp"

#include <filesystem>
#include <stdexcept>

#include "core/atomic_file.hpp"
#include "protocols/pair_file.hpp"
#include "protocols/pair_hash.hpp"

namespace regbench {

void CheckGenerateRequest(const GenerateRequest& request) {
    ValidateProtocolOptions(request.options);
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
    PairSet set = GeneratePairs(shapes, request.options, request.seed, num_pairs, progress);
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
