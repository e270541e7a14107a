#include "experiments/training.hpp"

#include <memory>
#include <sstream>
#include <stdexcept>

#include "datasets/dataset_shapes.hpp"
#include "experiments/experiment_file.hpp"
#include "protocols/pair_file.hpp"
#include "protocols/pair_protocols.hpp"

namespace regbench {
namespace {

std::vector<std::string> SplitList(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream in(s);
    for (std::string item; std::getline(in, item, ',');) {
        if (!item.empty()) out.push_back(item);
    }
    return out;
}

/// Shapes of every dataset in the comma-separated list, for one split.
std::vector<ShapeSource> LoadShapes(const TrainingDataOptions& a, const std::string& split) {
    DatasetOptions options;
    options.data_dir = a.data_dir;
    const ShapeLoader load = DatasetShapeLoader(options);
    std::vector<ShapeSource> shapes;
    for (const auto& name : SplitList(a.dataset)) {
        auto part = load(name, split);
        shapes.insert(shapes.end(), part.begin(), part.end());
    }
    if (shapes.empty()) {
        throw std::runtime_error("train: dataset '" + a.dataset + "' split '" + split +
                                 "' holds no shapes");
    }
    return shapes;
}

/// Training stream and validation pairs from a frozen pair file.
networks::TrainData FromPairFile(const TrainingDataOptions& a) {
    networks::TrainData data;
    auto set = std::make_shared<PairSet>(ReadPairFile(a.pairs_file));
    const std::size_t n = set->pairs.size();
    const auto n_val = static_cast<std::size_t>(a.val_fraction * static_cast<double>(n));
    if (n_val < 1 || n_val >= n) {
        throw std::invalid_argument("train: pair file " + a.pairs_file + " has " +
                                    std::to_string(n) + " pairs; --val-fraction " +
                                    std::to_string(a.val_fraction) +
                                    " leaves no training or no validation pair");
    }
    const std::size_t n_train = n - n_val;  // the last n_val pairs validate
    for (std::size_t i = n_train; i < n; ++i)
        data.validation.push_back(ToTrainSample(set->pairs[i]));
    data.train_pair = [set, n_train](std::uint64_t k) {
        return ToTrainSample(set->pairs[k % n_train]);
    };
    data.provenance = {{"pairs_file", a.pairs_file},
                       {"pairs_file_provenance", set->provenance},
                       {"train_pairs", n_train},
                       {"val_pairs", n_val}};
    return data;
}

}  // namespace

TrainingBundle LoadTrainingBundle(const TrainingDataOptions& a) {
    if (!a.pairs_file.empty()) {
        throw std::invalid_argument(
            "train: a training bundle is made from a protocol and "
            "datasets, not from --pairs-file");
    }
    TrainingBundle b;
    Protocol protocol = ParseProtocol(a.protocol);
    if (a.jitter && protocol == Protocol::kPartial) protocol = Protocol::kJitter;
    b.protocol = DefaultProtocolOptions(protocol);
    b.protocol.pairing = ParsePairing(a.pairing);
    ValidateProtocolOptions(b.protocol);
    b.train_shapes = LoadShapes(a, a.split);
    b.val_shapes = LoadShapes(a, a.val_split);
    b.val_pairs = a.val_pairs;
    b.seed = a.seed;
    b.provenance = {{"dataset", a.dataset}, {"split", a.split}, {"val_split", a.val_split}};
    return b;
}

networks::TrainData MakeTrainingData(const TrainingDataOptions& a) {
    if (!a.pairs_file.empty()) return FromPairFile(a);
    return MakeTrainingData(LoadTrainingBundle(a));
}

LearnedVariants AblationVariants(const std::string& kind) {
    std::vector<std::string> kinds;
    for (const auto& f : PaperPlan()) {
        const VariantSpec& v = f.variants;
        if (v.rows.empty()) continue;
        if (v.kind == kind) {
            LearnedVariants out{v.model, {}};
            for (const auto& r : v.rows) out.rows.emplace_back(r.row, r.config);
            return out;
        }
        kinds.push_back(v.kind);
    }
    std::string list;
    for (std::size_t i = 0; i < kinds.size(); ++i)
        list += (i == 0 ? "" : i + 1 == kinds.size() ? " or " : ", ") + kinds[i];
    throw std::invalid_argument("--ablation must be " + list + ", got '" + kind + "'");
}

}  // namespace regbench
