#pragma once
// What an import of the authors' weights takes besides the file: the options of
// `import-checkpoint` and the settings and presets a family declares (AuthorsFormat in
// networks/checkpoint/authors_format.hpp) for what no tensor of the authors' file fixes.
// JSON only: free of LibTorch types.
#include <nlohmann/json.hpp>
#include <string>

namespace regbench::networks {

struct ImportOptions {
    std::string from;  ///< the family whose authors saved the file, e.g. "deepgmr"
    /// A named preset of the family's import settings (the authors' per-dataset configs, e.g.
    /// RIENet's "7scenes"); "" = none.
    std::string preset;
    /// Import settings over the preset (`--setting key=value`): what no tensor of the file
    /// fixes. A JSON object; every key must be one the family declares.
    nlohmann::json settings = nlohmann::json::object();
};

/// One import setting a family declares: what no tensor of the authors' file fixes.
struct ImportSetting {
    std::string key;
    nlohmann::json default_value;  ///< the authors' default (their ModelNet40 config)
    std::string doc;
};

/// A named set of import settings: one of the authors' configs (e.g. their per-dataset YAML).
struct ImportPreset {
    std::string name;
    std::string doc;  ///< where it comes from and what it is for
    nlohmann::json values;
};

}  // namespace regbench::networks
