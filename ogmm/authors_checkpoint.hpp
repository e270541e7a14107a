#pragma once
// The authors' own checkpoints in and out of regbench: DeepGMR's (wentaoyuan/deepgmr,
// `DeepGMR(args).state_dict()`, e.g. the released modelnet_*.pth / icl_nuim.pth) and OGMM's
// (gfmei/ogmm, `GMMReg(emb_dims, n_clusters, config).state_dict()`). Import infers the
// architecture from tensor names and shapes, maps every tensor onto regbench's `deepgmr-orig*`
// / `ogmm` modules, refuses missing, unexpected or mis-shaped tensors by name, and writes a
// regbench checkpoint folder whose checkpoint.json records the source's sha256 and the mapping.
// Export writes the reverse: a zip-format .pth the authors' modules load strictly.
// This header is free of LibTorch types (callers outside ogmm/ compile without its headers);
// the state-dict level is in ogmm/authors_state_dict.hpp.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace regbench::ogmm {

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

/// The settings an import runs with: the family's defaults, then the preset's values, then
/// options.settings. `assumed` lists the keys neither the preset nor the user gave (defaults
/// the command reports it assumed). Throws std::invalid_argument naming an unknown family,
/// preset or key (listing the known ones) or a value of the wrong type.
struct ResolvedImportSettings {
    nlohmann::json values = nlohmann::json::object();
    std::vector<std::string> assumed;
};
ResolvedImportSettings ResolveImportSettings(const ImportOptions& options);

/// The import settings and presets family `from` declares (for --help, inspect and docs).
std::vector<ImportSetting> AuthorsImportSettings(const std::string& from);
std::vector<ImportPreset> AuthorsImportPresets(const std::string& from);

/// Pairs (authors' state-dict key, regbench parameter/buffer name) for a regbench config, in
/// the authors' module order. `from`: "deepgmr" or "ogmm".
std::vector<std::pair<std::string, std::string>> AuthorsKeyMapping(const std::string& from,
                                                                   const nlohmann::json& config);

/// Reads `pth`, checks and maps it, writes the checkpoint folder `out_dir` (atomically).
/// Returns the checkpoint.json written. Throws std::runtime_error naming the file and every
/// missing, unexpected or mis-shaped tensor.
nlohmann::json ImportAuthorsCheckpoint(const std::string& pth, const std::string& out_dir,
                                       const ImportOptions& options);

/// A .pth the authors' module `to` ("deepgmr" | "ogmm") loads strictly.
struct AuthorsPth {
    std::string bytes;        ///< zip-format torch.save of the state dict
    std::size_t tensors = 0;  ///< how many tensors it holds
};

/// The checkpoint in `dir` as the authors' module `to` would hold it (ExportAuthorsStateDict
/// in ogmm/authors_state_dict.hpp, serialised). Throws naming the folder when it is of another
/// family.
AuthorsPth ExportAuthorsPth(const std::string& dir, const std::string& to);

}  // namespace regbench::ogmm
