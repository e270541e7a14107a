// `regbench import-checkpoint` / `export-checkpoint`: the authors' PyTorch state dicts of every
// network family with an authors' format (DeepGMR, OGMM, OMNet, RIENet, RGM, REGTR; .pth, zip
// or legacy format) to and from regbench checkpoint folders (networks/checkpoint/authors_checkpoint.hpp).
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "app/cli_numbers.hpp"
#include "app/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/input_file.hpp"
#include "core/output_rule.hpp"
#include "core/sha256.hpp"
#ifdef REGBENCH_HAVE_LEARNED
#include "networks/checkpoint/authors_checkpoint.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/family.hpp"
#endif

namespace regbench::app {
namespace {

#ifdef REGBENCH_HAVE_LEARNED
struct ImportArgs {
    std::string file;
    std::string out;
    bool force = false;
    networks::ImportOptions options;
    std::vector<std::string> settings;  ///< --setting KEY=VALUE
};

/// `--setting KEY=VALUE` as a JSON object: VALUE is read as JSON when it parses (numbers,
/// true/false), else taken as a string. A later KEY wins; no '=' is refused naming the flag.
nlohmann::json ParseSettings(const std::vector<std::string>& items) {
    nlohmann::json out = nlohmann::json::object();
    for (const auto& item : items) {
        const auto eq = item.find('=');
        if (eq == std::string::npos || eq == 0) {
            throw CLI::ValidationError("--setting", "expected KEY=VALUE, got '" + item + "'");
        }
        const std::string value = item.substr(eq + 1);
        nlohmann::json v = nlohmann::json::parse(value, nullptr, false);
        if (v.is_discarded() || v.is_object() || v.is_array() || v.is_null()) v = value;
        out[item.substr(0, eq)] = v;
    }
    return out;
}

/// The --help footer: every family's import settings (defaults, meaning) and presets.
std::string SettingsHelp() {
    std::string out =
        "Settings no tensor fixes (--setting KEY=VALUE; defaults: the authors' ModelNet40 "
        "configs), and presets (--preset NAME), per --from family:\n";
    for (const auto& from : networks::AuthorsFormats()) {
        const auto settings = networks::AuthorsImportSettings(from);
        out += "  " + from +
               (settings.empty() ? ": none, its tensors fix the whole network\n" : ":\n");
        for (const auto& s : settings) {
            out += "    " + s.key + " = " + s.default_value.dump() + "  " + s.doc + "\n";
        }
        for (const auto& p : networks::AuthorsImportPresets(from)) {
            out += "    --preset " + p.name + ": " + p.values.dump() + " (" + p.doc + ")\n";
        }
    }
    return out;
}

/// The network families with an authors' checkpoint format (networks/family.hpp), "a | b".
std::string Formats() {
    std::string list;
    for (const auto& f : networks::AuthorsFormats()) list += (list.empty() ? "" : " | ") + f;
    return list;
}

void SetupImport(CLI::App* cmd) {
    auto a = std::make_shared<ImportArgs>();
    cmd->add_option("FILE", a->file, "The authors' torch.save state dict (.pth; zip or legacy)")
        ->required();
    cmd->add_option("--from", a->options.from, "Whose module saved it: " + Formats())
        ->required()
        ->check(CLI::IsMember(networks::AuthorsFormats()));
    cmd->add_option("--out", a->out, "Checkpoint folder to write")->required();
    cmd->add_flag("--force", a->force,
                  "Replace an existing --out checkpoint folder (never another folder: a "
                  "training run's, or one holding other files, is refused)");
    cmd->add_option("--preset", a->options.preset,
                    "One of the authors' named configs of the --from family (e.g. per dataset: "
                    "the settings no tensor of their file fixes); each family's are listed "
                    "below");
    cmd->add_option("--setting", a->settings,
                    "KEY=VALUE over the preset: a setting no tensor of the file fixes (each "
                    "family's keys, types and defaults are listed below); repeatable");
    cmd->footer(SettingsHelp());
    cmd->callback([a] {
        a->options.settings = ParseSettings(a->settings);
        // Refused before the file is read: an unknown preset or key, a value of the wrong type.
        const networks::ResolvedImportSettings resolved = networks::ResolveImportSettings(a->options);
        // A folder, a FIFO or a device is named as such, not as "no such file".
        RequireRegularFile(a->file);
        // The one output rule (docs/usage.md, "Outputs"): `--out m.pth` given the input m.pth,
        // or an existing training run folder, replaced them; one writer per checkpoint folder.
        OutputRule rule;
        rule.replace = a->force;
        rule.folder = true;
        const ClaimedOutput claim(a->out, {a->file}, rule);
        // Refused before the import's work; the save checks again.
        if (a->force) networks::RequireReplaceableCheckpointFolder(a->out);
        const nlohmann::json j = networks::ImportAuthorsCheckpoint(a->file, a->out, a->options);
        std::cout << "import-checkpoint: wrote " << a->out << " ("
                  << j.at("config").at("name").get<std::string>() << ", " << j.at("mapping").size()
                  << " tensors from a " << j.at("imported_from").at("format").get<std::string>()
                  << " file, sha256 " << j.at("imported_from").at("sha256").get<std::string>()
                  << ")\n"
                  << "  config: " << j.at("model_config").dump() << "\n";
        if (!resolved.assumed.empty()) {
            std::string assumed;
            for (const auto& k : resolved.assumed) {
                assumed += (assumed.empty() ? "" : ", ") + k + "=" + resolved.values.at(k).dump();
            }
            std::cout << "  assumed (no tensor, --preset or --setting gave them; the authors' "
                         "defaults): "
                      << assumed << "\n";
        }
    });
}

struct ExportArgs {
    std::string dir;
    std::string to;
    std::string out;
    bool force = false;
};

void SetupExport(CLI::App* cmd) {
    auto a = std::make_shared<ExportArgs>();
    cmd->add_option("DIR", a->dir, "regbench checkpoint folder")->required();
    cmd->add_option("--to", a->to, "Whose module will load it: " + Formats())
        ->required()
        ->check(CLI::IsMember(networks::AuthorsFormats()));
    cmd->add_option("--out", a->out, ".pth file to write (zip format, torch.load-able)")
        ->required();
    cmd->add_flag("--force", a->force, "Replace an existing --out");
    cmd->callback([a] {
        const ClaimedOutput claim(a->out, {a->dir}, OutputRule{a->force});
        const networks::AuthorsPth pth = networks::ExportAuthorsPth(a->dir, a->to);
        WriteFileAtomic(a->out, pth.bytes,
                        {(std::filesystem::path(a->dir) / "weights.pt").string(),
                         (std::filesystem::path(a->dir) / "checkpoint.json").string()});
        std::cout << "export-checkpoint: wrote " << a->out << " (" << pth.tensors
                  << " tensors, sha256 " << Sha256File(a->out) << ")\n";
    });
}
#else
void SetupImport(CLI::App* cmd) {
    cmd->callback(
        [] { throw std::runtime_error("import-checkpoint: this build has no LibTorch"); });
}
void SetupExport(CLI::App* cmd) {
    cmd->callback(
        [] { throw std::runtime_error("export-checkpoint: this build has no LibTorch"); });
}
#endif

[[maybe_unused]] const bool kImportRegistered = RegisterCommand(
    {"import-checkpoint",
     "Import the authors' PyTorch weights (.pth) of a learned method as a checkpoint folder",
     SetupImport});
[[maybe_unused]] const bool kExportRegistered = RegisterCommand(
    {"export-checkpoint",
     "Export a checkpoint folder as a .pth the authors' code of its family loads", SetupExport});
}  // namespace

}  // namespace regbench::app
