#pragma once
// The learned-method registry: one NetworkFamily per network family (DeepGMR, OGMM, ...). A
// family is one folder, networks/families/<family>/, whose family.cpp fills the NetworkFamily
// below, and one line of networks/families/families.def; the zoo, the cost model,
// checkpoints, the authors' checkpoint import, training, the learned regbench methods
// (baselines/learned.cpp) and the reports' paper rows ask the registry and name no family.
// This header is what a family must provide; docs/adding-a-learned-method.md walks through
// adding one.
// Free of LibTorch types: callers outside networks/ include it without LibTorch's headers.
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/registration.hpp"

namespace regbench::networks {

class RegistrationNet;  // networks/net.hpp
struct AuthorsFormat;   // networks/checkpoint/authors_format.hpp
struct ForwardCost;     // networks/cost.hpp

/// A regbench method a family contributes: its network on a pair, optionally refined by
/// Open3D point-to-point ICP (baselines/learned.cpp).
struct LearnedMethodSpec {
    std::string name;     ///< method name, e.g. "ogmm-noicp"
    bool icp = false;     ///< ICP refines the network's estimate (the icp_* parameters)
    std::string summary;  ///< one line for `regbench methods`
    /// The row of the OGMM paper's tables this method fills (e.g. "OGMM"); "" = none.
    std::string paper_label = {};
};

/// A config key that changes what the network computes at inference but none of its
/// parameters, so a checkpoint's weights load under another value (OGMM's "attention"). Each
/// is a string parameter of the family's methods: "" (the default) runs the checkpoint's value.
struct InferenceParam {
    std::string key;
    std::string doc;                   ///< for `regbench methods`: what each choice runs
    std::vector<std::string> choices;  ///< the values it may take besides ""
};

/// Everything regbench knows about one network family.
struct NetworkFamily {
    std::string arch;     ///< the config's "arch", e.g. "ogmm"; unique
    std::string summary;  ///< one line: the paper and what the network does
    /// Zoo model names of this family, in display order (`regbench train --model`).
    std::vector<std::string> models;
    /// Shipped checkpoint folder (data/models/<shipped_model>) its methods run by default.
    std::string shipped_model;
    /// Full configuration of a model of `models`: the network's keys with "arch" and "name",
    /// plus a "train" object with its training recipe (networks/training/train.hpp TrainConfig).
    std::function<nlohmann::json(const std::string& model)> named_config;
    /// One line per network config key (every key of named_config's models but "arch", "name"
    /// and "train"): meaning, unit, what it changes. `regbench train --list-models` prints
    /// them with each model's values; a test holds the two lists equal.
    std::map<std::string, std::string> config_docs;
    /// Parses and checks a network config (no "train"; "arch" and "name" allowed): unknown
    /// keys, wrong types and values out of range throw std::invalid_argument naming the key.
    /// Cheap: builds no network, so a checkpoint is checked before a run starts.
    std::function<void(const nlohmann::json& config)> check_config;
    /// Builds the network a checked config describes (no "train"; "arch" and "name" allowed).
    /// Its Forward is the family's inference, its Loss the training loss (networks/net.hpp).
    std::function<std::shared_ptr<RegistrationNet>(const nlohmann::json& config)> build;
    /// Multiply-accumulates of one batch-1 forward on n source and m target points
    /// (networks/cost.hpp: what is counted and what is not).
    std::function<ForwardCost(const nlohmann::json& config, std::int64_t n, std::int64_t m)>
        forward_cost;
    /// The config keys a run may change without touching the weights (`run --params`).
    std::vector<InferenceParam> inference_params;
    /// How the network's time grows with the cloud sizes, for the scale guard (runners/
    /// scale_guard.hpp): DGCNN's kNN Gram matrix and attention over all points are O(N * M).
    CostClass cost_class = CostClass::kQuadratic;
    /// The regbench methods the family contributes, in display order.
    std::vector<LearnedMethodSpec> methods;
    /// How the authors' published state dicts map onto regbench's parameters
    /// (`import-checkpoint --from <arch>`, `export-checkpoint --to <arch>`); null: no import.
    std::shared_ptr<const AuthorsFormat> authors;
};

/// Every family, in display order: the ones listed in networks/family.cpp, then any added by
/// RegisterFamily.
const std::vector<NetworkFamily>& Families();
/// Adds a family at run time, for code outside the tree (and the worked example's test). Call
/// it before the first use of the registry (a learned method, the zoo); a family whose arch,
/// model or method name is already taken is refused (std::invalid_argument).
void RegisterFamily(NetworkFamily family);
/// The family whose arch is `arch`; throws std::invalid_argument listing the known ones.
const NetworkFamily& FindFamily(const std::string& arch);
/// The family of a zoo config: its "arch"; a config without "arch" (checkpoints written before
/// the key existed) is of the first family that had checkpoints, OGMM.
const NetworkFamily& FamilyOfConfig(const nlohmann::json& config);
/// The family with zoo model `model`; throws std::invalid_argument listing every model.
const NetworkFamily& FamilyOfModel(const std::string& model);
/// The arches of the families with an authors' checkpoint format, for --from / --to.
std::vector<std::string> AuthorsFormats();

}  // namespace regbench::networks
