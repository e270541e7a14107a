#pragma once
// A training bundle: what `regbench train` makes its training and validation pairs from (the
// shapes of the training and validation splits, the pair protocol, the seed) and the resolved
// model config, in one file. A machine with LibTorch alone (a GPU node without Open3D, PCL,
// CGAL or HDF5) trains on the same pair stream from it: `regbench train ... --write-bundle
// FILE` here, `regbench-train-portable FILE --out DIR --device cuda` there (portable/). This
// file and its .cpp need core/, protocols/' pair generation and networks/training/train.hpp only, so
// portable/ compiles them in directly (docs/learned-methods.md, "Training on a GPU machine").
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "networks/training/train.hpp"
#include "protocols/pair_protocols.hpp"
#include "protocols/shape_source.hpp"

namespace regbench {

struct TrainingBundle {
    ProtocolOptions protocol;               ///< valid (ValidateProtocolOptions)
    std::vector<ShapeSource> train_shapes;  ///< mesh or point sources, never stored pairs
    std::vector<ShapeSource> val_shapes;
    int val_pairs = 200;     ///< validation pairs, drawn from val_shapes
    std::uint64_t seed = 0;  ///< training pair k = GeneratePair(train_shapes, protocol, seed, k)
    nlohmann::json provenance = nlohmann::json::object();  ///< dataset names and splits
    /// Written by `train --write-bundle` (null in a bundle made for a run here): the resolved
    /// model config with its "train" recipe, the command that wrote it, and whether that command
    /// fixed the run's length (--epochs), which keeps a --minutes budget from re-planning it.
    nlohmann::json config;
    std::string command;
    bool length_given = false;
};

/// A protocol pair as the trainer takes it: in the learned methods' frame (a pair outside the
/// training frame normalised as at inference, core/pair_normalization.hpp; others unchanged).
networks::TrainSample ToTrainSample(const Pair& p);

/// The training stream and validation pairs of `b` (what `regbench train` trains on).
networks::TrainData MakeTrainingData(const TrainingBundle& b);

/// Writes `b` to `path` (CBOR, atomically). Throws std::invalid_argument naming a stored-pair
/// shape (those come from pair files, which bundles do not carry) and std::runtime_error naming
/// `path` when it cannot be written.
void WriteTrainingBundle(const std::string& path, const TrainingBundle& b);

/// Reads a bundle; throws std::runtime_error naming `path` and the problem (missing, not a
/// bundle, another format version, a bad field or shape).
TrainingBundle ReadTrainingBundle(const std::string& path);

}  // namespace regbench
