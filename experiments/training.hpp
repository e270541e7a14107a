#pragma once
// The data `regbench train` learns from, and the paper's learned variants it trains with
// --ablation. Here, not in networks/: networks/ (the trainer) links core, gmm and LibTorch only, while
// training pairs come from datasets/ and protocols/ (docs/layout.md).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "experiments/training_bundle.hpp"
#include "networks/training/train.hpp"

namespace regbench {

/// Where training and validation pairs come from: a pair protocol over datasets, made on the
/// fly, or a frozen pair file (its last `val_fraction` validates).
struct TrainingDataOptions {
    std::string protocol = "partial";
    std::string dataset = "cgal,procedural";  ///< comma-separated names or paths
    std::string split = "train";
    std::string val_split = "val";
    std::string pairing = "shared";
    bool jitter = true;  ///< partial becomes jitter (both clouds jittered)
    std::string pairs_file;
    double val_fraction = 0.2;
    int val_pairs = 200;  ///< validation pairs of protocol data
    std::uint64_t seed = 0;
    std::string data_dir;  ///< where named datasets live ("" = the default)
};

/// The training stream and validation pairs; throws std::invalid_argument / runtime_error
/// naming the option or input ("train: ...").
networks::TrainData MakeTrainingData(const TrainingDataOptions& o);

/// The shapes, protocol and seed protocol data (no --pairs-file) come from, for
/// MakeTrainingData or a file (`train --write-bundle`). Its `config` and `command` are left
/// for the caller.
TrainingBundle LoadTrainingBundle(const TrainingDataOptions& o);

/// The learned variants of `kind` ("components", "losses", "clusters": the `variants` of the
/// paper's experiment files), each a paper row and its config overrides, and the model they
/// train over. Throws std::invalid_argument listing the kinds.
struct LearnedVariants {
    std::string model;
    std::vector<std::pair<std::string, nlohmann::json>> rows;
};
LearnedVariants AblationVariants(const std::string& kind);

}  // namespace regbench
