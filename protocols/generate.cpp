#include "protocols/generate.hpp"

#include <filesystem>
#include <stdexcept>

#include "protocols/pair_file.hpp"
#include "protocols/pair_hash.hpp"

namespace regbench {

void GenerateToFile(const GenerateRequest& request,
                    const ShapeLoader& load_shapes,
                    const ProgressCallback& progress) {
    ValidateProtocolOptions(request.options);
    if (request.num_pairs < 1) throw std::invalid_argument("generate: --pairs must be >= 1");
    if (request.out.empty()) throw std::invalid_argument("generate: --out is required");
    const std::filesystem::path out(request.out);
    const std::filesystem::path dir = out.has_parent_path() ? out.parent_path() : ".";
    if (!std::filesystem::is_directory(dir)) {
        throw std::invalid_argument(request.out + ": output directory " + dir.string() +
                                    " does not exist");
    }
    if (!load_shapes) throw std::invalid_argument("generate: no shape loader");
    const std::vector<ShapeSource> shapes = load_shapes(request.dataset, request.split);
    if (shapes.empty()) {
        throw std::runtime_error("dataset '" + request.dataset + "' split '" + request.split +
                                 "' has no shapes");
    }
    PairSet set = GeneratePairs(shapes, request.options, request.seed, request.num_pairs, progress);
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
