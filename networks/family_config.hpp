#pragma once
// A network family's config, declared once, the way a classical method declares its options
// (core/params.hpp): a plain struct with a default and a `///<` doc on every field,
//
//   template <class F> void Fields(F&& f) { f("iterations", iterations, "refinement rounds"); }
//   void Validate(ParamCheck& c) const { c.AtLeast("iterations", iterations, 1); ... }
//
// From that one declaration come the config's JSON (a checkpoint's model_config), its parsing
// with type and range checks (errors "<arch> config: parameter '<key>' must be <= 32, got
// 1000"), and the key docs of `regbench train --list-models` ("refinement rounds; range [1,
// 32]"). Every value has a range, so a config read from a checkpoint.json or inferred from an
// authors' file's tensor shapes is refused before a network is built from it. BindConfig fills
// a family's config_docs, check_config, build and forward_cost from the struct, its network
// and its MACs count; NetFamily starts a family from its zoo table, config and network.
// Free of LibTorch types; included by the families only.
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/params.hpp"
#include "networks/cost.hpp"
#include "networks/family.hpp"

namespace regbench::networks {

/// Whether Config's Fields bind `key`.
template <class Config>
bool DeclaresKey(const std::string& key) {
    bool found = false;
    Config c{};
    c.Fields([&](const char* k, auto& /*field*/, const char* /*doc*/,
                 Nullable /*nullable*/ = Nullable::kNo) { found = found || key == k; });
    return found;
}

/// Reads a family's config over Config's defaults. Zoo configs and checkpoints name their
/// family and model: "arch", when present, must be `arch`, and both it and "name" (unless
/// Config declares "name") are dropped first. Unknown keys, wrong types and values outside
/// Validate's ranges throw std::invalid_argument "<arch> config: parameter '<key>' ...".
template <class Config>
Config ParseNetConfig(const nlohmann::json& j, const std::string& arch) {
    nlohmann::json fields = j;
    if (j.is_object()) {
        if (j.contains("arch") && j.at("arch") != arch) {
            throw std::invalid_argument(arch + " config: arch is " + j.at("arch").dump());
        }
        fields.erase("arch");
        if (!DeclaresKey<Config>("name")) fields.erase("name");
    }
    return ParseParams<Config>(arch + " config", fields);
}

/// Validate's closed range [lo, hi] of an integer key: both bounds checked, and both in the
/// schema and the docs ("; range [lo, hi]").
template <class T>
void InRange(ParamCheck& c, const char* key, T value, std::common_type_t<T> lo,
             std::common_type_t<T> hi) {
    c.AtLeast(key, value, lo);
    c.AtMost(key, value, hi);
}
/// Validate's rule for a length, temperature or margin: a finite number > 0.
inline void Positive(ParamCheck& c, const char* key, double value) {
    c.Above(key, value, 0.0);
    c.Finite(key, value);
}
/// Validate's rule for a loss weight or threshold: a finite number >= 0.
inline void NonNegative(ParamCheck& c, const char* key, double value) {
    c.AtLeast(key, value, 0.0);
    c.Finite(key, value);
}

/// Validate's checks of a config built in code: the first value out of range throws as
/// ParseNetConfig does.
template <class Config>
void CheckNetConfig(const Config& c, const std::string& arch) {
    ParamCheck check(arch + " config");
    c.Validate(check);
}

/// Every field of `c` as JSON (enums by name), with "arch" when `arch` is not empty.
template <class Config>
nlohmann::json NetConfigJson(const Config& c, const std::string& arch) {
    nlohmann::json j = ParamsToJson(c);
    if (!arch.empty()) j["arch"] = arch;
    return j;
}

/// NetworkFamily::config_docs of Config: each field but "name", its doc and range.
template <class Config>
std::map<std::string, std::string> NetConfigDocs() {
    std::map<std::string, std::string> docs = ParamDocs<Config>();
    docs.erase("name");
    return docs;
}

/// One zoo model of a family: its name, what it changes in the config's defaults, and its
/// training recipe (the "train" object: networks/training/train.hpp TrainConfig).
template <class Config>
struct ZooModel {
    std::string name;
    std::function<void(Config&)> change;
    nlohmann::json train;
};

/// The full config of model `name` of `models` (NetworkFamily::named_config): Config's defaults
/// changed by the model, "name" set, as `to_json` writes them, with "train". An unknown name
/// throws std::invalid_argument listing the known ones.
template <class Config>
nlohmann::json ZooModelConfig(const std::vector<ZooModel<Config>>& models,
                              const std::string& name, nlohmann::json (*to_json)(const Config&)) {
    std::string known;
    for (const auto& m : models) {
        if (m.name != name) {
            known += (known.empty() ? "" : ", ") + m.name;
            continue;
        }
        Config c;
        c.name = name;
        m.change(c);
        nlohmann::json j = to_json(c);
        j["train"] = m.train;
        return j;
    }
    throw std::invalid_argument("unknown model '" + name + "' (known: " + known + ")");
}

/// Fills `f`'s models (in the table's order) and named_config from its model table.
template <class Config>
void BindModels(NetworkFamily& f, const std::vector<ZooModel<Config>>& models,
                nlohmann::json (*to_json)(const Config&)) {
    f.models.clear();
    for (const auto& m : models) f.models.push_back(m.name);
    f.named_config = [models, to_json](const std::string& name) {
        return ZooModelConfig(models, name, to_json);
    };
}

/// Multiply-accumulates of one batch-1 forward on n source and m target points, by part
/// (networks/cost.hpp), of a checked config.
template <class Config>
using ForwardMacsOf = std::map<std::string, std::int64_t> (*)(const Config& config, std::int64_t n,
                                                              std::int64_t m);

/// Fills `f`'s config_docs, check_config and build (f.arch set first): the config is read by
/// ParseNetConfig<Config>, the network is Net(config). With `macs`, also forward_cost: point
/// counts below 1 are refused, the config is read the same way and its parts summed.
template <class Config, class Net>
void BindConfig(NetworkFamily& f, ForwardMacsOf<Config> macs = nullptr) {
    const std::string arch = f.arch;
    f.config_docs = NetConfigDocs<Config>();
    f.check_config = [arch](const nlohmann::json& c) { ParseNetConfig<Config>(c, arch); };
    f.build = [arch](const nlohmann::json& c) -> std::shared_ptr<RegistrationNet> {
        return std::make_shared<Net>(ParseNetConfig<Config>(c, arch));
    };
    if (macs == nullptr) return;
    f.forward_cost = [arch, macs](const nlohmann::json& c, std::int64_t n, std::int64_t m) {
        if (n < 1 || m < 1) {
            throw std::invalid_argument(arch + " forward cost: point counts must be positive");
        }
        return CostOfParts(macs(ParseNetConfig<Config>(c, arch), n, m));
    };
}

/// A family whose zoo is the table `models` and whose network is Net built from a Config: arch,
/// summary, models and named_config (BindModels: configs as `to_json` writes them),
/// shipped_model (the table's first model), config_docs, check_config, build and, with `macs`,
/// forward_cost (BindConfig). What is left is particular to the family: cost_class, methods,
/// inference_params, authors.
template <class Config, class Net>
NetworkFamily NetFamily(std::string arch, std::string summary,
                        const std::vector<ZooModel<Config>>& models,
                        nlohmann::json (*to_json)(const Config&),
                        ForwardMacsOf<Config> macs = nullptr) {
    NetworkFamily f;
    f.arch = std::move(arch);
    f.summary = std::move(summary);
    BindModels(f, models, to_json);
    f.shipped_model = models.at(0).name;
    BindConfig<Config, Net>(f, macs);
    return f;
}

}  // namespace regbench::networks
