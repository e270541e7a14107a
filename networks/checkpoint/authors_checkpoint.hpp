#pragma once
// The authors' own checkpoints in and out of regbench: DeepGMR's (wentaoyuan/deepgmr,
// `DeepGMR(args).state_dict()`, e.g. the released modelnet_*.pth / icl_nuim.pth) and OGMM's
// (gfmei/ogmm, `GMMReg(emb_dims, n_clusters, config).state_dict()`). Import infers the
// architecture from tensor names and shapes, maps every tensor onto regbench's `deepgmr-orig*`
// / `ogmm` modules, refuses missing, unexpected or mis-shaped tensors by name, and writes a
// regbench checkpoint folder whose checkpoint.json records the source's sha256 and the mapping.
// Export writes the reverse: a zip-format .pth the authors' modules load strictly.
// This header is free of LibTorch types (callers outside networks/ compile without its headers);
// the state-dict level is in networks/checkpoint/authors_format.hpp.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "networks/checkpoint/import_settings.hpp"

namespace regbench::networks {

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
/// in networks/checkpoint/authors_format.hpp, serialised). Throws naming the folder when it is of another
/// family.
AuthorsPth ExportAuthorsPth(const std::string& dir, const std::string& to);

}  // namespace regbench::networks
