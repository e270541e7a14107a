#pragma once
// The state-dict level of the authors' import and export (networks/checkpoint/
// authors_checkpoint.hpp is its LibTorch-free face): the AuthorsFormat a network family
// declares (networks/family.hpp) to map the authors' state dicts onto its own, and the
// functions that take or return the authors' tensors themselves (LibTorch types).
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "networks/checkpoint/import_settings.hpp"
#include "networks/checkpoint/torch_save_reader.hpp"

namespace regbench::networks {

/// How a family's authors lay out their state dict (NetworkFamily::authors). An aggregate: a
/// family gives module and infer_config, then what it needs of the rest, in order.
struct AuthorsFormat {
    /// The authors' module and file, recorded in an imported checkpoint.json.
    std::string module;
    /// The regbench config (zoo form, with "arch", "name" and "train") the authors' state dict
    /// `tensors` of file `file` holds, read from its tensor names and shapes, and from
    /// `settings` (ResolveImportSettings: every key of `settings` below, checked for type) for
    /// what no shape fixes. Throws std::runtime_error naming the file and tensor.
    std::function<nlohmann::json(const StateDict& tensors, const std::string& file,
                                 const nlohmann::json& settings)>
        infer_config;
    /// What no tensor of the authors' file fixes (their defaults: the ModelNet40 config), the
    /// keys of `import-checkpoint --setting KEY=VALUE`; empty when the tensors fix everything.
    std::vector<ImportSetting> settings = {};
    /// The authors' named configs (`import-checkpoint --preset NAME`), e.g. per dataset.
    std::vector<ImportPreset> presets = {};
    /// The authors' key of regbench tensor `name`; unset: the same name.
    std::function<std::string(const std::string& name)> authors_name = {};
    /// Rank of an authors' key in their state_dict order (keys sort by it, stably); unset:
    /// regbench's order is theirs.
    std::function<int(const std::string& authors_key)> module_rank = {};
    /// Refuses (std::runtime_error naming `where`) a config the authors' module cannot hold;
    /// unset: every config of the family exports.
    std::function<void(const nlohmann::json& config, const std::string& where)> check_export =
        {};
};

/// The regbench model config (zoo form, with "arch", "name" and "train") the state dict
/// `tensors` of file `file` describes, as the family options.from reads it under the resolved
/// import settings of `options`. Throws std::runtime_error naming the file and tensor.
nlohmann::json InferAuthorsConfig(const StateDict& tensors, const std::string& file,
                                  const ImportOptions& options);

/// The state dict the authors' module of family `to` would have for the checkpoint in `dir`,
/// in their key order. Throws naming the folder when it is of another family.
StateDict ExportAuthorsStateDict(const std::string& dir, const std::string& to);

/// Throws std::runtime_error "<file>: <what>" (an authors' file that does not fit).
[[noreturn]] void RefuseAuthorsFile(const std::string& file, const std::string& what);

/// The tensor `key` of `sd` with `dims` dimensions; refuses the file naming the key when it is
/// missing ("not <network> state dict", listing the first keys it has) or of another rank.
const torch::Tensor& RequireAuthorsTensor(const StateDict& sd, const std::string& key,
                                          int64_t dims, const std::string& file,
                                          const std::string& network);

}  // namespace regbench::networks
